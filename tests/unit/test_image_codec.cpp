// PNG and PFM encoders: round trips and on-disk row order.
#include <gtest/gtest.h>

#include <zlib.h>

#include <cstring>
#include <string>
#include <vector>

#include "brdfa/image_codec.h"

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#endif
#include <stb/stb_image.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace brdfa {
namespace {

std::vector<uint8_t> testPattern(int w, int h) {
  std::vector<uint8_t> px(size_t(w) * h * 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &px[(size_t(y) * w + x) * 4];
      p[0] = uint8_t(x * 7 + y);
      p[1] = uint8_t(y * 13);
      p[2] = uint8_t((x ^ y) * 5);
      p[3] = uint8_t(255 - x);
    }
  return px;
}

std::vector<float> floatPattern(int w, int h) {
  std::vector<float> px(size_t(w) * h * 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* p = &px[(size_t(y) * w + x) * 4];
      p[0] = x + 0.25f;
      p[1] = -float(y) - 0.5f;
      p[2] = 1e-3f * float(x * y) + 100.0f;
      p[3] = 0.125f;  // not stored by PFM; decodes as 1
    }
  return px;
}

TEST(Png, RoundTripsThroughStbImage) {
  const int w = 37, h = 23;
  const std::vector<uint8_t> input = testPattern(w, h);
  const std::vector<uint8_t> png = encodePng(input.data(), w, h);
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(std::memcmp(png.data(), "\x89PNG\r\n\x1a\n", 8), 0);

  int dw = 0, dh = 0, channels = 0;
  stbi_uc* decoded = stbi_load_from_memory(png.data(), int(png.size()), &dw, &dh, &channels, 4);
  ASSERT_NE(decoded, nullptr) << stbi_failure_reason();
  EXPECT_EQ(dw, w);
  EXPECT_EQ(dh, h);
  EXPECT_EQ(channels, 4);
  EXPECT_EQ(std::memcmp(decoded, input.data(), input.size()), 0);
  stbi_image_free(decoded);
}

TEST(Png, OpaqueImagesAreWrittenAsRgbAndRoundTrip) {
  const int w = 37, h = 23;
  std::vector<uint8_t> input = testPattern(w, h);
  for (size_t i = 3; i < input.size(); i += 4) input[i] = 255;
  const std::vector<uint8_t> png = encodePng(input.data(), w, h);
  ASSERT_GT(png.size(), 26u);
  EXPECT_EQ(png[25], 2) << "IHDR colour type: 2 = RGB";

  int dw = 0, dh = 0, channels = 0;
  stbi_uc* decoded = stbi_load_from_memory(png.data(), int(png.size()), &dw, &dh, &channels, 4);
  ASSERT_NE(decoded, nullptr) << stbi_failure_reason();
  EXPECT_EQ(channels, 3);
  EXPECT_EQ(std::memcmp(decoded, input.data(), input.size()), 0);
  stbi_image_free(decoded);

  input[5 * 4 + 3] = 254;  // one pixel not opaque: RGBA (colour type 6)
  EXPECT_EQ(encodePng(input.data(), w, h)[25], 6);
}

TEST(Png, TextChunksTravelInsideTheFileAndStbStillDecodesIt) {
  const int w = 5, h = 4;
  const std::vector<uint8_t> input = testPattern(w, h);
  const std::vector<uint8_t> png =
      encodePng(input.data(), w, h, {{"brdfa:spp", "64"}, {"bad  keyword", "x"}, {"Comment", ""}});
  EXPECT_EQ(pngText(png, "brdfa:spp"), "64");
  EXPECT_EQ(pngText(png, "Comment"), "");
  EXPECT_EQ(pngText(png, "bad  keyword"), "") << "an invalid keyword is left out";
  EXPECT_EQ(pngText(png, "brdfa"), "") << "keywords match whole";
  EXPECT_EQ(pngText(encodePng(input.data(), w, h), "brdfa:spp"), "");
  EXPECT_EQ(pngText(std::vector<uint8_t>{1, 2, 3}, "brdfa:spp"), "");

  int dw = 0, dh = 0, channels = 0;
  stbi_uc* decoded = stbi_load_from_memory(png.data(), int(png.size()), &dw, &dh, &channels, 4);
  ASSERT_NE(decoded, nullptr) << stbi_failure_reason();  // stb checks no CRCs, but the layout must hold
  EXPECT_EQ(std::memcmp(decoded, input.data(), input.size()), 0);
  stbi_image_free(decoded);

  // Each chunk's CRC covers its type and data (zlib's crc32, as PNG specifies).
  const size_t at = 33;  // after the signature and IHDR
  const uint32_t length =
      (uint32_t(png[at]) << 24) | (uint32_t(png[at + 1]) << 16) | (uint32_t(png[at + 2]) << 8) | png[at + 3];
  ASSERT_EQ(std::string(png.begin() + at + 4, png.begin() + at + 8), "tEXt");
  const uint32_t crc = crc32(0, &png[at + 4], 4 + length);
  const uint8_t* stored = &png[at + 8 + length];
  EXPECT_EQ((uint32_t(stored[0]) << 24) | (uint32_t(stored[1]) << 16) | (uint32_t(stored[2]) << 8) | stored[3], crc);
}

TEST(Png, RejectsEmptyInput) {
  EXPECT_TRUE(encodePng(nullptr, 4, 4).empty());
  uint8_t px[4] = {};
  EXPECT_TRUE(encodePng(px, 0, 1).empty());
}

TEST(Pfm, HeaderAndBottomToTopRows) {
  const int w = 3, h = 2;
  const std::vector<float> input = floatPattern(w, h);
  const std::vector<uint8_t> pfm = encodePfm(input.data(), w, h);
  const std::string header = "PF\n3 2\n-1.0\n";
  ASSERT_EQ(pfm.size(), header.size() + size_t(w) * h * 3 * 4);
  EXPECT_EQ(std::string(pfm.begin(), pfm.begin() + header.size()), header);

  // The first row on disk is the last image row (y = h - 1), little-endian RGB.
  const uint8_t* data = pfm.data() + header.size();
  for (int x = 0; x < w; ++x)
    for (int c = 0; c < 3; ++c) {
      float v;
      std::memcpy(&v, data + (x * 3 + c) * 4, 4);  // the test host is little-endian (x86/arm)
      EXPECT_EQ(v, input[(size_t(h - 1) * w + x) * 4 + c]) << x << "," << c;
    }
}

TEST(Pfm, RoundTrip) {
  const int w = 17, h = 9;
  const std::vector<float> input = floatPattern(w, h);
  const std::vector<uint8_t> pfm = encodePfm(input.data(), w, h);
  int dw = 0, dh = 0;
  std::vector<float> out;
  ASSERT_TRUE(decodePfm(pfm, dw, dh, out));
  ASSERT_EQ(dw, w);
  ASSERT_EQ(dh, h);
  ASSERT_EQ(out.size(), input.size());
  for (size_t i = 0; i < input.size(); ++i) EXPECT_EQ(out[i], i % 4 == 3 ? 1.0f : input[i]) << "index " << i;
}

TEST(Pfm, DecodesGreyAndBigEndian) {
  // "Pf" greyscale, big-endian (positive scale), 2x1, bottom row first (only one row here).
  const std::string header = "Pf\n2 1\n1.0\n";
  std::vector<uint8_t> bytes(header.begin(), header.end());
  for (float v : {0.5f, -2.0f}) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    for (int i = 3; i >= 0; --i) bytes.push_back(uint8_t(bits >> (8 * i)));
  }
  int w = 0, h = 0;
  std::vector<float> out;
  ASSERT_TRUE(decodePfm(bytes, w, h, out));
  ASSERT_EQ(w, 2);
  ASSERT_EQ(h, 1);
  const std::vector<float> expected = {0.5f, 0.5f, 0.5f, 1.0f, -2.0f, -2.0f, -2.0f, 1.0f};
  EXPECT_EQ(out, expected);
}

TEST(Pfm, RejectsMalformed) {
  int w = 0, h = 0;
  std::vector<float> out;
  auto bytesOf = [](const std::string& s) { return std::vector<uint8_t>(s.begin(), s.end()); };
  EXPECT_FALSE(decodePfm(bytesOf(""), w, h, out));
  EXPECT_FALSE(decodePfm(bytesOf("P6\n1 1\n255\nabc"), w, h, out));
  EXPECT_FALSE(decodePfm(bytesOf("PF\n1 1\n-1.0\n"), w, h, out));  // no raster
  EXPECT_FALSE(decodePfm(bytesOf("PF\nx 1\n-1.0\n000000000000"), w, h, out));
  EXPECT_FALSE(decodePfm(bytesOf("PF\n1 1\n0\n000000000000"), w, h, out));  // zero scale
  EXPECT_TRUE(decodePfm(bytesOf("PF\n1 1\n-1.0\n000000000000"), w, h, out));
}

}  // namespace
}  // namespace brdfa
