// Equirectangular (latitude-longitude) environment images and their conversion to the internal
// cube map (environment_maps.h).
//
// Mapping, for a unit world direction d (+Y up, the default camera at +Z looking down -Z):
//   u = 0.5 + atan2(d.x, -d.z) / (2 pi)    (column, 0 at the left edge, 1 at the right)
//   v = acos(d.y) / pi                      (row, 0 at the top edge = +Y, 1 at the bottom = -Y)
// so the image centre (u, v) = (0.5, 0.5) is seen looking down -Z, u = 0.75 is +X, u = 0.25 is
// -X and the left/right edges are +Z (behind the default camera). Turning right from -Z (to +X)
// moves right in the image: the panorama is seen unmirrored from the centre.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "assets/environment_maps.h"

namespace brdfa {

// Linear RGB float pixels, row 0 at the top.
struct FloatImage {
  int width = 0, height = 0;
  std::vector<float> rgb;  // width * height * 3
};

// (u, v) in [0, 1] of unit direction `dir` (see above).
void equirectUv(const float dir[3], float& u, float& v);

// Cube face size for an equirect `width` wide: width / 4 (a face spans a quarter of the
// horizon) rounded to the nearest power of two, clamped to [16, 1024].
uint32_t equirectFaceSize(int width);

// Resamples an equirect image into the internal cube. Each row is first averaged along u over
// a box as wide as a cube texel there (rows near the poles hold a circle of latitude in many
// pixels), then each cube texel is the mean of n x n stratified bilinear lookups over its area
// (u wraps around, v clamps), n growing with the number of image rows the texel spans, so sharp
// features are averaged rather than aliased. Values are stored as they are: sanitise first.
EnvironmentData equirectToCube(FloatImage image, const std::string& name);

}  // namespace brdfa
