// Built-in environments, generated on the CPU into one internal form: an RGBA16F cubemap.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "brdfa/result.h"

namespace brdfa {

struct EnvironmentData {
  std::string name;
  bool constant = false;  // radiance 1 in every direction (the furnace): kernels skip lookups
  uint32_t faceSize = 1;
  std::vector<float> texels;  // linear RGBA, faces +X -X +Y -Y +Z -Z, rows top to bottom; never clipped
};

// The cube as uploaded: RGBA16F (the format whose linear filtering Vulkan guarantees) holding
// texels / scale, with `scale` a power of two >= 1 chosen so the brightest texel fits the half
// range (65504). The kernels multiply by `scale` with the environment's intensity, so no
// radiance is clipped: a sun of 1e6 keeps its energy, at half precision (11 significant bits).
struct HalfCube {
  std::vector<uint16_t> texels;
  float scale = 1.0f;
};
HalfCube packHalfCube(const EnvironmentData& env);

// "furnace" (radiance 1 everywhere), "sky" (daylight with a sun), "studio" (three rectangular
// area lights over a dim grey surround), "cornell" (inside a Cornell-box-like room).
std::vector<std::string> builtinEnvironmentNames();

// NotFound for an unknown name.
Result<EnvironmentData> makeBuiltinEnvironment(const std::string& name);

// World direction through the point (s, t) of cube face `face`, s and t in [-1, 1] running
// along the face's columns (left to right) and rows (top to bottom); normalised. This is the
// Vulkan/GL cube map convention (Vulkan spec, "Cube Map Face Selection", table 'Cube map face
// selection and transformations', read backwards).
void cubeFaceDirection(int face, float s, float t, float dir[3]);

// World direction through the centre of texel (x, y) of cube face `face` (Vulkan/GL convention).
void cubeTexelDirection(int face, uint32_t x, uint32_t y, uint32_t size, float dir[3]);

// World direction through the centre of stratum (i, j) of an n x n grid over texel (x, y):
// the points averaged when a texel is filtered. n = 1 is cubeTexelDirection.
void cubeTexelStratumDirection(int face, uint32_t x, uint32_t y, uint32_t size, int i, int j, int n, float dir[3]);

// Solid angle (steradians) that texel (x, y) of a cube face of `size` x `size` texels subtends;
// the same for every face. The six faces together sum to 4 pi.
double cubeTexelSolidAngle(uint32_t x, uint32_t y, uint32_t size);

// The cube face holding unit direction `dir` and the point (s, t) in [-1, 1] on it where the
// direction meets the face: the inverse of cubeFaceDirection.
void cubeFaceCoords(const float dir[3], int& face, float& s, float& t);

// Linear RGB radiance arriving from unit direction `dir`.
using DirectionLookup = std::function<void(const float dir[3], float rgb[3])>;
// How many lookups per axis texel (x, y) of `face` averages (>= 1).
using StrataPerAxis = std::function<int(int face, uint32_t x, uint32_t y)>;

// A cube of `size` x `size` texels per face, each texel the mean of `lookup` over an n x n
// grid of strata (cubeTexelStratumDirection), n from `strata`: a box filter over the texel's
// area, so edges sharper than a texel come out antialiased. Alpha is 1.
EnvironmentData makeFilteredCube(const std::string& name, uint32_t size, const DirectionLookup& lookup,
                                 const StrataPerAxis& strata);

}  // namespace brdfa
