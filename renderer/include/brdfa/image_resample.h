// Resampling of display frames (8-bit, already tone mapped and sRGB encoded).
#pragma once

#include <cstdint>
#include <vector>

namespace brdfa {

// Halves an RGBA8 image (row 0 at the top) by averaging each 2x2 block, rounding to nearest.
// The average is of the stored sRGB codes, not of radiance: it is for previews on screen, never
// for measurements. An odd last row or column is dropped. `outWidth` x `outHeight` is
// (width/2) x (height/2); empty (and 0 x 0) when either input side is below 2 or rgba8 is null.
std::vector<uint8_t> halveRgba8(const uint8_t* rgba8, int width, int height, int& outWidth, int& outHeight);

}  // namespace brdfa
