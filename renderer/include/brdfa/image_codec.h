// Encoders for frames leaving the service: PNG (display), PFM and EXR (linear float radiance).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace brdfa {

// PNG of 8-bit RGBA rows (row 0 at the top). Uses libdeflate level 1 and the Sub filter: many
// times faster than stb's defaults for a few percent larger files, which suits a live stream.
// An image whose alpha is 255 everywhere is written as RGB (colour type 2), else as RGBA.
std::vector<uint8_t> encodePng(const uint8_t* rgba8, int width, int height);

// The same with tEXt chunks (keyword, text) after the header, e.g. {"brdfa:spp", "64"}: data
// that travels inside the file. A keyword must be 1-79 printable Latin-1 characters without a
// leading, trailing or double space; pairs that are not are left out.
std::vector<uint8_t> encodePng(const uint8_t* rgba8, int width, int height,
                               const std::vector<std::pair<std::string, std::string>>& text);

// The text of tEXt chunk `keyword` in a PNG, or "" when there is none (or it is not a PNG).
std::string pngText(const std::vector<uint8_t>& png, const std::string& keyword);

// Portable float map ("PF", RGB, little-endian, scale -1). PFM stores rows bottom to top; the
// input is row 0 at the top, as everywhere else in this project.
std::vector<uint8_t> encodePfm(const float* rgba32f, int width, int height);

// OpenEXR (scanline, ZIP-compressed, 32-bit float) of linear radiance, through tinyexr. The
// input is RGBA floats, row 0 at the top (EXR stores rows top to bottom, so it stays there);
// `alpha` false writes R, G, B only (as PFM does), true adds A. Empty on failure (bad
// arguments, or tinyexr's error, which goes to `error` when given).
std::vector<uint8_t> encodeExr(const float* rgba32f, int width, int height, bool alpha = false,
                               std::string* error = nullptr);

// Parses a PFM written by encodePfm (or any "PF"/"Pf" file) into RGBA floats, row 0 at the top.
// Returns false on malformed input. Used by tests and tools.
bool decodePfm(const std::vector<uint8_t>& bytes, int& width, int& height, std::vector<float>& rgba32f);

}  // namespace brdfa
