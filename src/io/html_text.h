// Text for the self-contained HTML reports (ilc, diagnose): escaping and embedded images.
#pragma once

#include <string>

#include "io/png_image.h"

namespace twinsim {

// `s` with <, >, & and " replaced by their entities.
std::string HtmlEscape(const std::string& s);

// An <img> element holding `image` as an embedded PNG (a data: URL), with `alt` text.
std::string HtmlImage(const RgbaImage& image, const std::string& alt);

}  // namespace twinsim
