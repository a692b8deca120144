#include "assets/equirect.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace brdfa {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

void equirectUv(const float dir[3], float& u, float& v) {
  u = static_cast<float>(0.5 + std::atan2(dir[0], -dir[2]) / (2.0 * kPi));
  // acos is undefined just outside [-1, 1], where a normalised vector's y can land by rounding.
  v = static_cast<float>(std::acos(std::clamp(dir[1], -1.0f, 1.0f)) / kPi);
}

uint32_t equirectFaceSize(int width) {
  const uint32_t kMin = 16, kMax = 1024;
  if (width < 4 * static_cast<int>(kMin)) return kMin;  // also keeps log2 away from 0
  int exponent = static_cast<int>(std::lround(std::log2(width / 4.0)));
  return std::clamp(uint32_t(1) << std::min(exponent, 30), kMin, kMax);
}

namespace {

// Bilinear lookup at (u, v) with texel centres at ((x + 0.5) / width, (y + 0.5) / height);
// columns wrap around (the left and right edges meet at +Z), rows clamp at the poles.
void sampleBilinear(const FloatImage& image, float u, float v, float out[3]) {
  const int w = image.width, h = image.height;
  float px = u * static_cast<float>(w) - 0.5f;
  float py = std::clamp(v * static_cast<float>(h) - 0.5f, 0.0f, static_cast<float>(h - 1));
  float fx0 = std::floor(px), fy0 = std::floor(py);
  float fx = px - fx0, fy = py - fy0;
  // u in [0, 1] puts px in [-0.5, w - 0.5], so x0 is in [-1, w - 1]: one wrap at most.
  int x0 = static_cast<int>(fx0);
  if (x0 < 0) x0 += w;
  if (x0 >= w) x0 -= w;
  int x1 = x0 + 1 == w ? 0 : x0 + 1;
  int y0 = static_cast<int>(fy0), y1 = std::min(y0 + 1, h - 1);
  const float* p00 = &image.rgb[(size_t(y0) * w + x0) * 3];
  const float* p10 = &image.rgb[(size_t(y0) * w + x1) * 3];
  const float* p01 = &image.rgb[(size_t(y1) * w + x0) * 3];
  const float* p11 = &image.rgb[(size_t(y1) * w + x1) * 3];
  for (int c = 0; c < 3; ++c) {
    float top = p00[c] + (p10[c] - p00[c]) * fx;
    float bottom = p01[c] + (p11[c] - p01[c]) * fx;
    out[c] = top + (bottom - top) * fy;
  }
}

// Rows toward the poles hold the same circle of latitude in ever more pixels: a pixel of row
// y spans 2 pi / width * sin(theta) radians along u, so near a pole one cube texel (about
// 2 / faceSize radians) covers dozens of pixels of its row. Averaging each row over a box that
// wide (a running sum, wrapping in u) filters that direction once per row, in O(pixels), and
// leaves the per-texel lookups only the latitude direction to cover.
void prefilterRows(FloatImage& image, uint32_t faceSize) {
  const int w = image.width, h = image.height;
  std::vector<double> row(size_t(w) * 3);
  for (int y = 0; y < h; ++y) {
    double sinTheta = std::sin(kPi * (y + 0.5) / h);
    double span = (2.0 / faceSize) / (2.0 * kPi / w * sinTheta);
    // A box of 2 r + 1 pixels, never wider than the row (the window must not wrap onto itself).
    int r = std::min((w - 1) / 2, static_cast<int>(span / 2));
    if (r < 1) continue;
    float* pixels = &image.rgb[size_t(y) * w * 3];
    std::copy(pixels, pixels + size_t(w) * 3, row.begin());
    double sum[3] = {0, 0, 0};
    for (int i = -r; i <= r; ++i)
      for (int c = 0; c < 3; ++c) sum[c] += row[size_t((i + w) % w) * 3 + c];
    for (int x = 0; x < w; ++x) {
      size_t enter = size_t((x + r + 1) % w) * 3, leave = size_t((x - r + w) % w) * 3;
      for (int c = 0; c < 3; ++c) {
        pixels[size_t(x) * 3 + c] = static_cast<float>(sum[c] / (2 * r + 1));
        sum[c] += row[enter + c] - row[leave + c];
      }
    }
  }
}

// Lookups per axis for a cube texel: about one per image row the texel spans, plus one (the
// rows have been filtered along u already). A texel at (s, t) on a face of `size` subtends
// about (2 / size)^2 / (1 + s^2 + t^2)^(3/2) steradians, so it spans the square root of that in
// radians; a row is pi / height high. Clamped to [2, 16]: at least 2 x 2 stratified bilinear
// lookups smooth every texel, and 16 x 16 cover an image 16 times finer than the cube.
int lookupsPerAxis(uint32_t x, uint32_t y, uint32_t size, int height) {
  double s = 2.0 * (x + 0.5) / size - 1.0, t = 2.0 * (y + 0.5) / size - 1.0;
  double texelAngle = (2.0 / size) / std::pow(1.0 + s * s + t * t, 0.75);
  double rowAngle = kPi / height;
  return static_cast<int>(std::clamp(std::ceil(texelAngle / rowAngle) + 1.0, 2.0, 16.0));
}

}  // namespace

EnvironmentData equirectToCube(FloatImage image, const std::string& name) {
  const uint32_t size = equirectFaceSize(image.width);
  prefilterRows(image, size);
  return makeFilteredCube(
      name, size,
      [&image](const float dir[3], float rgb[3]) {
        float u, v;
        equirectUv(dir, u, v);
        sampleBilinear(image, u, v, rgb);
      },
      [&image, size](int, uint32_t x, uint32_t y) { return lookupsPerAxis(x, y, size, image.height); });
}

}  // namespace brdfa
