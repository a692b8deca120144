#include "render/host_resolve.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <system_error>
#include <thread>

namespace brdfa {

namespace {

double srgbDecode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }
double srgbEncode(double c) { return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055; }

// Encoding by table. thresholds[k] is the linear value from which the output is at least k+1
// (the decode of the midpoint between codes k and k+1). coarse[] maps the top 16 bits of a
// float (sign, exponent, 7 mantissa bits) to the code at the bottom of that bucket; a bucket
// spans less than one code, so one comparison with the next threshold gives the exact code.
struct SrgbTables {
  std::array<float, 256> thresholds;
  std::array<uint8_t, 65536> coarse;
  SrgbTables() {
    for (int k = 0; k < 255; ++k) thresholds[k] = static_cast<float>(srgbDecode((k + 0.5) / 255.0));
    thresholds[255] = INFINITY;
    for (uint32_t hi = 0; hi < 65536; ++hi) {
      uint32_t bits = hi << 16;
      float lo;
      std::memcpy(&lo, &bits, sizeof lo);
      int code = 0;
      if (lo > 0 && std::isfinite(lo)) {
        double e = srgbEncode(std::min<double>(lo, 1.0)) * 255.0 + 0.5;
        code = static_cast<int>(e);
        // Step down if rounding of pow put the code above the exact threshold rule.
        while (code > 0 && lo < thresholds[code - 1]) --code;
      } else if (std::isinf(lo) && lo > 0) {
        code = 255;
      }
      coarse[hi] = static_cast<uint8_t>(code);
    }
  }
};

const SrgbTables& tables() {
  static const SrgbTables t;
  return t;
}

// Same bound as BRDFA_TONE_MAX in tonemap.glsl: every curve has reached 1 far below it, and
// it keeps Inf / Inf (NaN) out of the rational curves.
constexpr float kToneMax = 1.0e6f;

// The three curves of tonemap.glsl, on e already clamped to [0, kToneMax].
float toneClamp(float e) { return std::min(e, 1.0f); }
// Reinhard et al. 2002, eq. 3.
float toneReinhard(float e) { return e / (1.0f + e); }
// Narkowicz 2015, ACES filmic fit, clamped to [0, 1].
float toneAces(float e) {
  constexpr float a = 2.51f, b = 0.03f, c = 2.43f, d = 0.59f, f = 0.14f;
  return std::clamp((e * (a * e + b)) / (e * (c * e + d) + f), 0.0f, 1.0f);
}

// The per-pixel loop, specialised per tone map so the choice is made once per frame.
template <float (*Tone)(float)>
void resolvePixels(const HostResolveInput& in, size_t begin, size_t end, uint8_t* rgba8, float* rgba32f,
                   ErrorSums& sums) {
  const float* a = in.accum;
  const float* b = in.accum + 4 * in.pixels;
  for (size_t i = begin; i < end; ++i) {
    const float* pa = a + 4 * i;
    const float* pb = b + 4 * i;
    const float n = pa[3] + pb[3];
    float mean[3] = {0, 0, 0};
    if (n > 0) {  // guard: no samples yet
      for (int c = 0; c < 3; ++c) mean[c] = (pa[c] + pb[c]) / n;
    }
    if (rgba8) {
      for (int c = 0; c < 3; ++c) {
        const float e = mean[c] * in.exposureScale;
        // !(e > 0) also sends NaN to 0, as linearToSrgb8 does.
        rgba8[4 * i + c] = linearToSrgb8(e > 0.0f ? Tone(std::min(e, kToneMax)) : 0.0f);
      }
      rgba8[4 * i + 3] = 255;
    }
    if (rgba32f) {
      for (int c = 0; c < 3; ++c) rgba32f[4 * i + c] = mean[c];
      rgba32f[4 * i + 3] = 1.0f;
    }
    if (in.surface[2 * i] != 0 && pa[3] > 0 && pb[3] > 0) {
      // Same estimate as resolve.comp.glsl: (mA - mB)^2 / ((1/nA + 1/nB)(nA + nB)).
      double d = luminance(pa[0] / pa[3], pa[1] / pa[3], pa[2] / pa[3]) -
                 luminance(pb[0] / pb[3], pb[1] / pb[3], pb[2] / pb[3]);
      sums.variance += d * d / ((1.0 / pa[3] + 1.0 / pb[3]) * n);
      sums.luminance += luminance(mean[0], mean[1], mean[2]);
      sums.pixels += 1;
    }
  }
}

}  // namespace

float luminance(float r, float g, float b) { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }

float toneMapValue(float e, ToneMap toneMap) {
  if (!(e > 0.0f)) return 0.0f;  // also NaN
  e = std::min(e, kToneMax);
  switch (toneMap) {
    case ToneMap::Reinhard: return toneReinhard(e);
    case ToneMap::Aces: return toneAces(e);
    case ToneMap::Clamp: break;
  }
  return toneClamp(e);
}

uint8_t linearToSrgb8(float x) {
  const SrgbTables& t = tables();
  if (!(x > 0.0f)) return 0;  // also NaN
  if (x >= 1.0f) return 255;
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  uint8_t code = t.coarse[bits >> 16];
  return static_cast<uint8_t>(code + (x >= t.thresholds[code] ? 1 : 0));
}

ErrorSums resolveOnHost(const HostResolveInput& in, uint8_t* rgba8, float* rgba32f) {
  auto range = [&](size_t begin, size_t end) {
    ErrorSums sums;
    switch (in.toneMap) {
      case ToneMap::Reinhard: resolvePixels<toneReinhard>(in, begin, end, rgba8, rgba32f, sums); break;
      case ToneMap::Aces: resolvePixels<toneAces>(in, begin, end, rgba8, rgba32f, sums); break;
      case ToneMap::Clamp: resolvePixels<toneClamp>(in, begin, end, rgba8, rgba32f, sums); break;
    }
    return sums;
  };
  // Two halves on two threads: the device is idle while a frame is read (the read happens
  // between passes), and a stream frame waits for it.
  // Below kSplitPixels a thread's start costs more than it saves.
  constexpr size_t kSplitPixels = 1u << 16;
  if (in.pixels < kSplitPixels) return range(0, in.pixels);
  const size_t half = in.pixels / 2;
  ErrorSums second;
  std::thread helper;
  try {
    helper = std::thread([&] { second = range(half, in.pixels); });
  } catch (const std::system_error&) {  // no thread to be had (a process at its limit): one core
    return range(0, in.pixels);
  }
  ErrorSums sums = range(0, half);
  helper.join();
  sums.variance += second.variance;
  sums.luminance += second.luminance;
  sums.pixels += second.pixels;
  return sums;
}

double relativeError(const ErrorSums& s) {
  if (s.pixels <= 0 || s.luminance <= 0) return -1;
  return std::sqrt(s.variance / s.pixels) / (s.luminance / s.pixels);
}

}  // namespace brdfa
