#include "render/image_stack.h"

#include <algorithm>

#include "render/raster.h"

namespace twinsim {

RgbaImage StackImages(const RgbaImage& top, const RgbaImage& bottom) {
  RgbaImage out(std::max(top.width, bottom.width), top.height + bottom.height);
  raster::Paste(out, top, 0, 0);
  raster::Paste(out, bottom, 0, top.height);
  return out;
}

}  // namespace twinsim
