#include "brdfa/image_resample.h"

#include <cstddef>

namespace brdfa {

std::vector<uint8_t> halveRgba8(const uint8_t* rgba8, int width, int height, int& outWidth, int& outHeight) {
  outWidth = outHeight = 0;
  if (!rgba8 || width < 2 || height < 2) return {};
  const int w = width / 2, h = height / 2;
  std::vector<uint8_t> out(size_t(w) * h * 4);
  const size_t stride = size_t(width) * 4;
  for (int y = 0; y < h; ++y) {
    const uint8_t* top = rgba8 + size_t(2 * y) * stride;
    const uint8_t* bottom = top + stride;
    uint8_t* dst = &out[size_t(y) * w * 4];
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 4; ++c) {
        const size_t i = size_t(x) * 8 + c;
        dst[x * 4 + c] = uint8_t((top[i] + top[i + 4] + bottom[i] + bottom[i + 4] + 2) / 4);
      }
  }
  outWidth = w;
  outHeight = h;
  return out;
}

}  // namespace brdfa
