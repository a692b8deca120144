#include "assets/environment_preview.h"

#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <cmath>

namespace brdfa {

std::vector<uint32_t> previewRadianceEntries(const EnvironmentData& env, float scale) {
  const uint32_t F = std::max<uint32_t>(env.faceSize, 1), P = kPreviewCellsPerEdge;
  std::vector<uint32_t> entries(2 * size_t(kPreviewEntries));
  for (uint32_t face = 0; face < 6; ++face)
    for (uint32_t cy = 0; cy < P; ++cy)
      for (uint32_t cx = 0; cx < P; ++cx) {
        // The texels whose centres lie in the cell, or the one under its centre where none do.
        const auto range = [&](uint32_t c, uint32_t& lo, uint32_t& hi) {
          const double perCell = double(F) / P;
          lo = uint32_t(std::max(0.0, std::ceil(c * perCell - 0.5)));
          hi = std::min(F, uint32_t(std::max(0.0, std::ceil((c + 1) * perCell - 0.5))));
          if (hi <= lo) {
            lo = std::min(F - 1, uint32_t((c + 0.5) * perCell));
            hi = lo + 1;
          }
        };
        uint32_t x0, x1, y0, y1;
        range(cx, x0, x1);
        range(cy, y0, y1);
        double rgb[3] = {0, 0, 0}, area = 0;
        for (uint32_t y = y0; y < y1; ++y)
          for (uint32_t x = x0; x < x1; ++x) {
            const double w = cubeTexelSolidAngle(x, y, F);
            const float* t = &env.texels[4 * ((size_t(face) * F + y) * F + x)];
            for (int c = 0; c < 3; ++c) rgb[c] += w * t[c];
            area += w;
          }
        const size_t at = 2 * ((size_t(face) * P + cy) * P + cx);
        // GLSL's packHalf2x16: the first value in the low 16 bits.
        const auto half = [&](int c) -> uint32_t { return glm::packHalf1x16(float(rgb[c] / area / scale)); };
        entries[at] = half(0) | half(1) << 16;
        entries[at + 1] = half(2);
      }
  return entries;
}

}  // namespace brdfa
