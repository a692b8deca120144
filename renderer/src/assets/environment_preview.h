// The coarse environment the preview kernel reads (shaders/lib/environment_preview.glsl):
// the cube averaged over 6 x P x P cells, appended to the environment's table on the device.
#pragma once

#include <cstdint>
#include <vector>

#include "assets/environment_maps.h"

namespace brdfa {

// log2 of P, the preview's cells per face edge. 16: a cell is ~6 degrees wide, small against
// any lobe a preview has to show, and the 1536 entries (12 KiB) stay in a CPU's L1 cache.
inline constexpr uint32_t kPreviewLog2Cells = 4;
inline constexpr uint32_t kPreviewCellsPerEdge = 1u << kPreviewLog2Cells;
inline constexpr uint32_t kPreviewEntries = 6 * kPreviewCellsPerEdge * kPreviewCellsPerEdge;

// Per cell (face, row, column order, as the cube's texels), two words: packHalf2x16(r, g) and
// packHalf2x16(b, 0) of the cell's mean radiance divided by `scale` (the cube's: HalfCube), each
// texel weighted by its solid angle, so a cell's radiance times its solid angle is the map's
// integral over it. A face of fewer than P texels repeats its texels over the cells they cover.
std::vector<uint32_t> previewRadianceEntries(const EnvironmentData& env, float scale);

}  // namespace brdfa
