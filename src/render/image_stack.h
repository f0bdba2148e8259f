// Stacking images into one: two plots that share an axis (a Bode plot's magnitude over
// its phase) drawn as one PNG. The wider image sets the width; white fills the space
// beside the narrower one.
//
//   RgbaImage bode = StackImages(RenderSeriesPlot(magnitude, r), RenderSeriesPlot(phase, r));
#pragma once

#include "io/png_image.h"

namespace twinsim {

// `top` above `bottom`, both flush left, in an image as wide as the wider and as high as
// both together (px); pixels neither covers are opaque white.
RgbaImage StackImages(const RgbaImage& top, const RgbaImage& bottom);

}  // namespace twinsim
