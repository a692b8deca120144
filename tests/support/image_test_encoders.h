// Encoders for the image-decoding and upload tests: every test input is made in memory with stb_image_write,
// tinyexr and OpenEXR, the libraries' own writers, so the decoders are checked against
// independent code (tinyexr's EXR writer in particular shares no code with the OpenEXR reader).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace brdfa::testing {

// 8-bit images, `channels` interleaved values per pixel, row 0 at the top.
std::string encodePng(int width, int height, int channels, const std::vector<uint8_t>& pixels);
std::string encodeJpeg(int width, int height, int channels, const std::vector<uint8_t>& pixels, int quality = 95);

// Radiance RGBE (run-length scanlines when 8 <= width < 32768) of linear RGB floats.
std::string encodeHdr(int width, int height, const std::vector<float>& rgb);

// OpenEXR with R, G, B channels of linear RGB floats, stored as half or float, with a tinyexr
// compression type (TINYEXR_COMPRESSIONTYPE_*; ZIP by default).
std::string encodeExr(int width, int height, const std::vector<float>& rgb, bool half, int compression = 3);

// What OpenEXR's own writer makes and tinyexr cannot: DWAA/DWAB, B44(A), PXR24, multi-part and
// deep files, single-channel grey images.
struct OpenExrOptions {
  // An Imf::Compression: 0 NONE, 1 RLE, 2 ZIPS, 3 ZIP, 4 PIZ, 5 PXR24, 6 B44, 7 B44A, 8 DWAA, 9 DWAB.
  int compression = 9;
  bool half = true;    // HALF channels, else FLOAT
  bool tiled = false;  // 16 x 16 tiles, one level, else scanlines
  bool grey = false;   // one Y channel with the green values, else R, G, B and an A of 0.5
  int parts = 1;       // 2: a multi-part file, the image in part 0 and a one-pixel "Z" part after it
  bool deep = false;   // a deep scanline image, one sample per pixel (single part, not tiled)
};

// OpenEXR (Imf::OutputFile and its tiled, multi-part and deep kin, into an in-memory
// Imf::OStream) with the data window (0, 0)-(width - 1, height - 1).
std::string encodeExrWithOpenExr(int width, int height, const std::vector<float>& rgb,
                                 const OpenExrOptions& options = {});

// sRGB encoding of a linear value in [0, 1] as a byte (IEC 61966-2-1).
uint8_t linearToSrgbByte(float linear);

}  // namespace brdfa::testing
