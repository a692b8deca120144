// The signed difference of two renders of one view (the side-by-side view: two BRDFs, or two
// parameter sets, under the same camera and environment), with its relative RMS and the error
// bar that both images' own noise gives it. Host-only: no device work.
#pragma once

#include <cstdint>
#include <vector>

#include "brdfa/renderer.h"

namespace brdfa {

struct FrameDifference {
  int width = 0;
  int height = 0;
  // A - B in luminance, drawn with a diverging colour map: blue where B is brighter, white where
  // they agree, red where A is brighter; +-range reach the ends of the map (sRGB, opaque).
  std::vector<uint8_t> rgba8;
  std::vector<float> signedLuminance;  // A - B per pixel, row 0 at the top
  double range = 0;
  // Relative RMS difference over the P object pixels of A's error estimate
  // (FrameStats::errorPixels), against A's mean luminance there, with the noise of both
  // estimates taken out:
  //   D^2 = sum over all pixels of (A - B)^2 / P - sA^2 - sB^2,  relRms = sqrt(max(D^2, 0)) / mean(A),
  // where sA^2, sB^2 are the mean variances of the pixels' estimates ((relError *
  // errorMeanLuminance)^2 of each frame). This assumes what a side-by-side view has: the same
  // camera, geometry and environment, so both cover the same pixels and the background (noise
  // free) is identical. relRmsError is its standard error: Var(D^2) = 2 Var_p((A - B)^2) / P,
  // the pixels' own spread of the squared difference (Monte Carlo noise is heavy-tailed, so no
  // Gaussian formula will do), once for the mean square and once for the noise estimates taken
  // from the same samples; where A and B truly differ it also counts the image's variation
  // (conservative). Carried through the square root: sigma(D^2) / (2 D), or sqrt(sigma(D^2))
  // where D is too small for that first-order form. The two renders must be independent
  // (different render.seed): the correction assumes their noise does not correlate.
  double relRms = 0;
  double relRmsError = 0;
  double rawRelRms = 0;   // the same without the noise correction
  double noiseFloor = 0;  // sqrt(sA^2 + sB^2) / mean(A): the per-pixel noise, relative
  uint64_t pixels = 0;    // P
};

// `a` and `b` are linear frames (Frame::rgba32f) of equal size, with their stats (the
// relError of the moment each was read). range <= 0 picks the 99th percentile of |A - B| over
// the compared pixels. InvalidArgument when the sizes differ or either frame lacks linear
// data or an error estimate.
Result<FrameDifference> differenceOf(const Frame& a, const Frame& b, double range = 0);

}  // namespace brdfa
