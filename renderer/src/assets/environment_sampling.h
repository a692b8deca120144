// Importance sampling of an environment cube map: a piecewise-constant distribution
// over cells of the cube's faces, in proportion to each cell's luminance times its solid
// angle, drawn on the device in O(1) by Walker's alias method (Vose's construction; as in
// pbrt-v4's AliasTable). Built once per environment and kept with it.
//
// Within a cell, directions are drawn uniformly in the face's (s, t) coordinates, so the
// density in solid angle is exact everywhere, cube seams included:
//   pdf(w) = P(cell) / (cell area in s,t) * |d(s,t)/d(w)| = P(cell) * (D/2)^2 / |w_major|^3,
// w_major the component of the unit direction along the face's axis (dA = r^3 dw, r^2 =
// 1 + s^2 + t^2 = 1 / w_major^2). shaders/lib/environment_sampling.glsl reads the table.
#pragma once

#include <cstdint>
#include <vector>

#include "assets/environment_maps.h"

namespace brdfa {

struct EnvironmentDistribution {
  uint32_t cellsPerEdge = 0;    // D: cells per face edge (a face is D x D cells), a power of two
  double effectiveDensity = 0;  // integral of pdf^2 over the sphere: how concentrated it is
  // 2 words an entry, read by the device as one RG32UI texel (on lavapipe a 64-bit texel fetch
  // costs a fraction of a 128-bit one). Entry 0: (log2 D, bits of effectiveDensity as float).
  // Entry 1 + c for cell c = (face * D + row) * D + column:
  //   word 0: alias_c << kAliasShift | k_c: the alias method keeps cell c when 13 random bits
  //           are below k_c (so with probability k_c / 8192), else takes alias_c (itself when
  //           the cell needs no alias);
  //   word 1: bits of density_c as float, density = P(cell) * (D/2)^2 with P(cell) the
  //           probability the table realises, so pdf(w) = density / |w_major|^3 is exactly the
  //           density of the draws (up to float rounding).
  static constexpr uint32_t kAliasShift = 13;  // 6 * 256^2 cells need 19 bits
  std::vector<uint32_t> table;

  // Decoded entry fields, for tests and host checks.
  uint32_t keepThreshold(size_t cell) const { return table[2 * (cell + 1)] & ((1u << kAliasShift) - 1u); }
  uint32_t aliasOf(size_t cell) const { return table[2 * (cell + 1)] >> kAliasShift; }
  float density(size_t cell) const;

  // The density in solid angle of the device sampler at unit direction `dir`, computed as the
  // device does; for tests and host checks.
  double pdf(const float dir[3]) const;
  // P(cell c) as the alias table realises it: (q_c + sum over cells aliasing to c of 1 - q) / n,
  // q = k / 8192.
  std::vector<double> realisedCellProbabilities() const;
  // The header alone, for a constant environment (log2 D = 0 and no cells; never sampled).
  static std::vector<uint32_t> constantHeader();
};

// Cells: the cube's texels, or groups of texels: D is the largest power of two up to both the
// face size and `maxCellsPerEdge`.
// A cell's weight is the integral of the bilinearly filtered radiance's luminance over it
// (each texel's luminance blurred by [1/8, 3/4, 1/8] in s and t, the exact cell integral of the
// tent each texel spreads into its neighbours), times the cell's solid angle, plus a uniform floor
// holding 1e-4 of the total weight, so every direction where the filtered map is non-zero has a
// non-zero density (seams included). A black environment becomes uniform over the
// sphere (up to the |w_major|^3 variation inside each cell).
// The default of 128 keeps the table at 768 KiB, within a CPU's L2 cache: its reads are
// random, and on lavapipe a larger table ran mis at fewer samples/s with no lower error at
// equal time in any bench scene (a 0.7-degree cell still holds most of a small sun's light).
inline constexpr uint32_t kMaxCellsPerEdge = 128;
EnvironmentDistribution buildEnvironmentDistribution(const EnvironmentData& env,
                                                     uint32_t maxCellsPerEdge = kMaxCellsPerEdge);

}  // namespace brdfa
