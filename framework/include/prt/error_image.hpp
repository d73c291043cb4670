// A render's error against its reference as images a paper can use: the
// magnitude in a perceptual colour ramp with a labelled colour bar (PNG),
// and the signed difference in linear radiance (for OpenEXR).
#pragma once
#include "prt/image.hpp"

namespace prt {

struct ErrorHeatMap {
  Image8 image;     // the heat map, with the colour bar to its right
  double top = 0;   // the error at the bar's top (larger errors show its colour)
  double peak = 0;  // the largest error in the image
};

// Per pixel the Rec. 709 luminance of |render - truth| times `exposure` (1 is
// the display's white), on a viridis-like ramp from 0 to the 99th percentile
// of the pixels that differ, with a bar labelled in those units.
ErrorHeatMap error_heat_map(const Image& render, const Image& truth, float exposure);

// render - truth per channel, linear (negative where the render is darker).
Image signed_difference(const Image& render, const Image& truth);

}  // namespace prt
