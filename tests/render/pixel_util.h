// Pixel checks the render tests share.
#pragma once

#include <cstdint>
#include <cstdlib>

#include "render/renderer.h"

namespace twinsim::testing {

// Sum of the absolute channel differences of an RGBA pixel from a colour.
inline int ColorDistance(const std::uint8_t* p, Color c) {
  return std::abs(p[0] - c.r) + std::abs(p[1] - c.g) + std::abs(p[2] - c.b);
}

}  // namespace twinsim::testing
