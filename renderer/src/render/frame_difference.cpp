// differenceOf (frame_difference.h).
#include "brdfa/frame_difference.h"

#include <algorithm>
#include <cmath>

#include "render/host_resolve.h"

namespace brdfa {

namespace {

// Diverging map (blue, white, red) of t in [-1, 1], linear RGB before the sRGB encoding.
void diverging(float t, uint8_t* rgba) {
  t = std::clamp(t, -1.0f, 1.0f);
  const float a = std::fabs(t);
  const float r = t > 0 ? 1.0f : 1.0f - a, g = 1.0f - a, b = t < 0 ? 1.0f : 1.0f - a;
  rgba[0] = linearToSrgb8(r);
  rgba[1] = linearToSrgb8(g);
  rgba[2] = linearToSrgb8(b);
  rgba[3] = 255;
}

}  // namespace

Result<FrameDifference> differenceOf(const Frame& a, const Frame& b, double range) {
  if (a.width != b.width || a.height != b.height)
    return makeError(ErrorCode::InvalidArgument, "the two views differ in size (" + std::to_string(a.width) + "x" +
                                                     std::to_string(a.height) + " and " + std::to_string(b.width) +
                                                     "x" + std::to_string(b.height) + ")");
  const size_t pixels = size_t(a.width) * size_t(a.height);
  if (a.rgba32f.size() != 4 * pixels || b.rgba32f.size() != 4 * pixels)
    return makeError(ErrorCode::InvalidArgument, "a difference needs both frames' linear radiance");
  if (!a.stats.relError || !b.stats.relError || a.stats.errorPixels == 0 || a.stats.errorMeanLuminance <= 0)
    return makeError(ErrorCode::InvalidArgument, "a difference needs both views' error estimates: wait for samples");

  FrameDifference out;
  out.width = a.width;
  out.height = a.height;
  out.signedLuminance.resize(pixels);
  double sumSq = 0, sumFourth = 0;
  std::vector<float> magnitudes;
  for (size_t i = 0; i < pixels; ++i) {
    const float* pa = &a.rgba32f[4 * i];
    const float* pb = &b.rgba32f[4 * i];
    float d = luminance(pa[0], pa[1], pa[2]) - luminance(pb[0], pb[1], pb[2]);
    if (!std::isfinite(d)) d = 0;  // guard: a non-finite pixel (dropped samples) adds nothing
    out.signedLuminance[i] = d;
    sumSq += double(d) * d;
    sumFourth += double(d) * d * double(d) * d;
    if (d != 0) magnitudes.push_back(std::fabs(d));
  }
  if (range <= 0) {
    if (!magnitudes.empty()) {
      auto at = magnitudes.begin() + std::min(magnitudes.size() - 1, magnitudes.size() * 99 / 100);
      std::nth_element(magnitudes.begin(), at, magnitudes.end());
      range = *at;
    }
    if (range <= 0) range = 1e-6;  // guard: identical images
  }
  out.range = range;
  out.rgba8.resize(4 * pixels);
  for (size_t i = 0; i < pixels; ++i) diverging(float(out.signedLuminance[i] / range), &out.rgba8[4 * i]);

  const double p = double(a.stats.errorPixels);
  const double mean = a.stats.errorMeanLuminance;
  const double sa = *a.stats.relError * a.stats.errorMeanLuminance;
  const double sb = *b.stats.relError * b.stats.errorMeanLuminance;
  const double s = sa * sa + sb * sb;
  const double raw = sumSq / p;
  const double d2 = raw - s;
  // The spread of the pixels' (A - B)^2 (Monte Carlo noise is heavy-tailed: a sun in the
  // environment), twice: once for the mean square, once for the noise estimate S taken from
  // the same samples. Where A and B truly differ this also counts how the difference varies
  // over the image: conservative.
  const double spread = std::max(sumFourth / p - raw * raw, 0.0);
  const double sigmaD2 = std::sqrt(2.0 * spread / p);
  out.pixels = a.stats.errorPixels;
  out.rawRelRms = std::sqrt(raw) / mean;
  out.noiseFloor = std::sqrt(s) / mean;
  out.relRms = std::sqrt(std::max(d2, 0.0)) / mean;
  const double firstOrder = d2 > 0 ? sigmaD2 / (2.0 * std::sqrt(d2)) : INFINITY;
  out.relRmsError = std::min(firstOrder, std::sqrt(sigmaD2)) / mean;
  return out;
}

}  // namespace brdfa
