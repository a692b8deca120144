// Importance sampling of an environment cube map (issue 11): a piecewise-constant distribution
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

#include "environment_maps.h"

namespace brdfa {

struct EnvironmentDistribution {
  uint32_t cellsPerEdge = 0;      // D: cells per face edge (a face is D x D cells), a power of two
  double effectiveDensity = 0;    // integral of pdf^2 over the sphere: how concentrated it is
  // 4 floats an entry. Entry 0: (D, effectiveDensity, log2 D, 0). Entry 1 + c for cell
  // c = (face * D + row) * D + column: (q_c, alias_c (an integer, exact in a float), density_c,
  // density_alias_c),
  // density = P(cell) * (D/2)^2, so pdf(w) = density / |w_major|^3.
  std::vector<float> table;

  // The density in solid angle of the device sampler at unit direction `dir`, computed as the
  // device does; for tests and host checks.
  double pdf(const float dir[3]) const;
  // P(cell c) as the alias table realises it: (q_c + sum over cells aliasing to c of 1 - q) / n.
  std::vector<double> realisedCellProbabilities() const;
};

// Cells: the cube's texels, or groups of texels: D is the largest power of two up to both the
// face size and `maxCellsPerEdge`.
// A cell's weight is the integral of the bilinearly filtered radiance's luminance over it
// (each texel's luminance blurred by [1/8, 3/4, 1/8] in s and t, the exact cell integral of the
// tent each texel spreads into its neighbours), times the cell's solid angle, plus a uniform floor
// holding 1e-4 of the total weight, so every direction where the filtered map is non-zero has a
// non-zero density (seams included). A black environment becomes uniform over the
// sphere (up to the |w_major|^3 variation inside each cell).
EnvironmentDistribution buildEnvironmentDistribution(const EnvironmentData& env, uint32_t maxCellsPerEdge = 256);

}  // namespace brdfa
