// The resolve (accumulators -> displayed frame + error partial sums) in C++, for CPU Vulkan
// devices: there "device memory" is host memory, and a plain loop reads it far faster than a
// compute kernel, whose storage-buffer accesses become per-lane bounds-checked loads. It is
// the same computation as shaders/kernels/resolve.comp.glsl (tests compare the two).
#pragma once

#include <cstddef>
#include <cstdint>

#include "brdfa/scene.h"

namespace brdfa {

struct ErrorSums {
  double variance = 0;   // sum over object pixels of the combined mean's variance estimate
  double luminance = 0;  // sum over object pixels of the mean's luminance
  double pixels = 0;     // object pixels with samples in both halves
};

struct HostResolveInput {
  const float* accum = nullptr;       // 2 * pixels RGBA: half A then half B (rgb sum, count)
  const uint32_t* surface = nullptr;  // pixels x 2, the G-buffer's surface plane (x != 0: object)
  size_t pixels = 0;
  float exposureScale = 1;
  ToneMap toneMap = ToneMap::Clamp;  // applied after exposure, before the sRGB encoding
};

// Writes rgba8 (sRGB, exposure applied; may be null) and rgba32f (linear mean; may be null);
// returns the error sums.
ErrorSums resolveOnHost(const HostResolveInput& in, uint8_t* rgba8, float* rgba32f);

// The tone map of an exposed radiance value e (one channel), into [0, 1]; the same formulas as
// shaders/lib/tonemap.glsl (see ToneMap in scene.h). Negative maps to 0, +Inf to 1.
float toneMapValue(float e, ToneMap toneMap);

// Exact 8-bit sRGB encoding of a linear value (IEC 61966-2-1, rounded to nearest), clamped to
// [0, 1]; NaN maps to 0.
uint8_t linearToSrgb8(float linear);

// rel_error from the sums: sqrt(mean variance) / mean luminance; negative when undefined.
double relativeError(const ErrorSums& sums);

// Rec. 709 luminance of linear RGB: the quantity the error estimates are measured in.
float luminance(float r, float g, float b);

}  // namespace brdfa
