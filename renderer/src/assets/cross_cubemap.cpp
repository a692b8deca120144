#include "assets/cross_cubemap.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace brdfa {

Result<void> checkCrossSize(int width, int height) {
  if (width > 0 && width % 4 == 0 && height == width / 4 * 3) return {};
  return makeError(ErrorCode::InvalidArgument,
                   "a PNG or JPEG environment must be a horizontal-cross cube map, 4 faces wide and 3 high "
                   "(width / 4 = height / 3, e.g. 1024x768); this image is " +
                       std::to_string(width) + "x" + std::to_string(height));
}

namespace {

// sRGB-encoded byte -> linear value (IEC 61966-2-1 decoding curve), tabulated once.
const std::array<float, 256>& srgbToLinearTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
      double c = i / 255.0;
      t[i] = static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
    }
    return t;
  }();
  return table;
}

// Where each face sits in the cross, in face units, indexed by the label's cube face number
// (+X -X +Y -Y +Z -Z, the order of cubeFaceCoords).
constexpr int kCrossColumn[6] = {2, 0, 1, 1, 1, 3};
constexpr int kCrossRow[6] = {1, 1, 0, 2, 1, 1};

struct Cross {
  const uint8_t* rgba;
  int width;
  int faceSize;
};

// Linear radiance the cross shows in world direction `dir` (nearest pixel). The cross's labels
// are a left-handed frame (cross_cubemap.h): flipping z turns our direction into the label
// direction, and the label's faces are laid out exactly as the GL/Vulkan cube convention
// (cubeFaceCoords) reads them, unrotated; that is why the usual cross has continuous edges.
void crossLookup(const Cross& cross, const float dir[3], float rgb[3]) {
  const float label[3] = {dir[0], dir[1], -dir[2]};
  int face;
  float s, t;
  cubeFaceCoords(label, face, s, t);
  const int n = cross.faceSize;
  // Clamping keeps s or t = 1 exactly (a face edge) on the face's last pixel.
  int col = std::clamp(static_cast<int>(std::floor((s + 1.0f) * 0.5f * n)), 0, n - 1);
  int row = std::clamp(static_cast<int>(std::floor((t + 1.0f) * 0.5f * n)), 0, n - 1);
  size_t x = size_t(kCrossColumn[face]) * n + col, y = size_t(kCrossRow[face]) * n + row;
  const uint8_t* p = cross.rgba + (y * cross.width + x) * 4;
  const auto& linear = srgbToLinearTable();
  for (int c = 0; c < 3; ++c) rgb[c] = linear[p[c]];
}

}  // namespace

EnvironmentData crossToCube(const uint8_t* rgba, int width, int height, const std::string& name) {
  // checkCrossSize has made width / 4 = height / 3; the min keeps lookups inside the image
  // even for a caller that did not check.
  const Cross cross{rgba, width, std::min(width / 4, height / 3)};
  // Up to 1024 (the equirect maximum) one lookup at each texel centre copies the face exactly;
  // above it, enough stratified lookups per texel to cover every source pixel.
  const uint32_t size = static_cast<uint32_t>(std::min(cross.faceSize, 1024));
  const int strata = size == static_cast<uint32_t>(cross.faceSize) ? 1 : (cross.faceSize + 1023) / 1024 + 1;
  return makeFilteredCube(
      name, size, [&cross](const float dir[3], float rgb[3]) { crossLookup(cross, dir, rgb); },
      [strata](int, uint32_t, uint32_t) { return strata; });
}

}  // namespace brdfa
