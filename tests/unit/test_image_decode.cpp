// Textures from files (PNG, JPEG through stb_image) and the built-in textures.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "assets/image_decode.h"
#include "image_test_encoders.h"

namespace brdfa {
namespace {

using namespace testing;  // the image encoders

std::vector<uint8_t> rgbaPattern(int w, int h) {
  std::vector<uint8_t> px(size_t(w) * h * 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &px[(size_t(y) * w + x) * 4];
      p[0] = uint8_t(x * 9 + y);
      p[1] = uint8_t(y * 17);
      p[2] = uint8_t((x ^ y) * 7);
      p[3] = uint8_t(200 + x % 50);
    }
  return px;
}

// A smooth image, so JPEG keeps it close.
std::vector<uint8_t> smoothRgb(int w, int h) {
  std::vector<uint8_t> px(size_t(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &px[(size_t(y) * w + x) * 3];
      p[0] = uint8_t(255 * x / (w - 1));
      p[1] = uint8_t(255 * y / (h - 1));
      p[2] = 128;
    }
  return px;
}

void expectInvalid(const Result<TextureData>& r, const std::string& needle) {
  ASSERT_FALSE(r.ok()) << "expected an error mentioning '" << needle << "'";
  EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
}

// Offset of the first byte of the data of the first PNG chunk of `type`.
size_t pngChunkData(const std::string& png, const std::string& type) {
  size_t at = png.find(type);
  EXPECT_NE(at, std::string::npos) << type;
  return at + 4;
}

// Rewrites the CRC of the chunk whose data starts at `data` and is `length` bytes long: the
// CRC-32 of the PNG spec (annex D) over the chunk's type and data.
void fixPngCrc(std::string& png, size_t data, size_t length) {
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = data - 4; i < data + length; ++i) {
    crc ^= static_cast<unsigned char>(png[i]);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  crc ^= 0xFFFFFFFFu;
  for (int i = 0; i < 4; ++i) png[data + length + i] = char(crc >> (24 - 8 * i));
}

// A valid 1x1 PNG whose IHDR is then changed by `edit` (CRC kept valid).
template <class Edit>
std::string forgedPng(Edit edit) {
  std::string png = encodePng(1, 1, 4, {1, 2, 3, 4});
  size_t ihdr = pngChunkData(png, "IHDR");
  edit(png, ihdr);
  fixPngCrc(png, ihdr, 13);
  return png;
}

TEST(ImageDecode, PngRoundTripIsExact) {
  auto px = rgbaPattern(37, 23);
  auto tex = decodeTexture(encodePng(37, 23, 4, px), AssetLimits{});
  ASSERT_TRUE(tex.ok()) << tex.error().message;
  EXPECT_EQ(tex->width, 37u);
  EXPECT_EQ(tex->height, 23u);
  EXPECT_EQ(tex->rgba8, px);
}

TEST(ImageDecode, GreyAndRgbPngBecomeRgba) {
  std::vector<uint8_t> grey = {0, 64, 128, 255};
  auto tex = decodeTexture(encodePng(2, 2, 1, grey), AssetLimits{});
  ASSERT_TRUE(tex.ok()) << tex.error().message;
  std::vector<uint8_t> expected = {0, 0, 0, 255, 64, 64, 64, 255, 128, 128, 128, 255, 255, 255, 255, 255};
  EXPECT_EQ(tex->rgba8, expected);
}

TEST(ImageDecode, JpegRoundTripIsClose) {
  auto px = smoothRgb(64, 48);
  auto tex = decodeTexture(encodeJpeg(64, 48, 3, px, 95), AssetLimits{});
  ASSERT_TRUE(tex.ok()) << tex.error().message;
  ASSERT_EQ(tex->width, 64u);
  ASSERT_EQ(tex->height, 48u);
  int worst = 0;
  for (size_t i = 0; i < size_t(64) * 48; ++i) {
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(int(tex->rgba8[i * 4 + c]) - int(px[i * 3 + c])));
    EXPECT_EQ(tex->rgba8[i * 4 + 3], 255);
  }
  EXPECT_LE(worst, 12);
}

TEST(ImageDecode, RejectsWhatIsNotPngOrJpeg) {
  expectInvalid(decodeTexture("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n", AssetLimits{}),
                "not a PNG or JPEG image");
  expectInvalid(decodeTexture("", AssetLimits{}), "not a PNG or JPEG image");
  expectInvalid(decodeTexture("v 0 0 0\n", AssetLimits{}), "not a PNG or JPEG image");
}

TEST(ImageDecode, ChecksThePixelLimitFromTheHeader) {
  AssetLimits limits;
  limits.maxPixels = 32 * 32 - 1;
  expectInvalid(decodeTexture(encodePng(32, 32, 4, rgbaPattern(32, 32)), limits), "32x32");
  expectInvalid(decodeTexture(encodeJpeg(32, 32, 3, smoothRgb(32, 32)), limits), "the limit is 1023 pixels");
  // The limit applies before decoding: a header declaring 16384 x 16384 pixels over one
  // pixel's data is refused for its size, not for its data (nor does it allocate 1 GiB).
  auto declaring = [](uint8_t hi, uint8_t lo) {
    return forgedPng([=](std::string& png, size_t ihdr) {
      const char size[4] = {0, 0, char(hi), char(lo)};
      png.replace(ihdr, 4, size, 4);
      png.replace(ihdr + 4, 4, size, 4);
    });
  };
  expectInvalid(decodeTexture(declaring(0x40, 0x00), AssetLimits{}), "16384x16384");
  // Past stb_image's own bound (2^30 bytes decoded) its header parser refuses first.
  expectInvalid(decodeTexture(declaring(0xFF, 0xFF), AssetLimits{}), "too large");
}

TEST(ImageDecode, TruncatedPngAndJpegAreRefused) {
  std::string png = encodePng(40, 40, 4, rgbaPattern(40, 40));
  expectInvalid(decodeTexture(png.substr(0, png.size() / 2), AssetLimits{}), "PNG");
  expectInvalid(decodeTexture(png.substr(0, png.size() / 2), AssetLimits{}), "truncated");
  expectInvalid(decodeTexture(png.substr(0, 20), AssetLimits{}), "PNG");
  std::string jpeg = encodeJpeg(64, 48, 3, smoothRgb(64, 48));
  expectInvalid(decodeTexture(jpeg.substr(0, jpeg.size() / 2), AssetLimits{}), "JPEG");
  expectInvalid(decodeTexture(jpeg.substr(0, jpeg.size() / 2), AssetLimits{}), "truncated");
  expectInvalid(decodeTexture(jpeg.substr(0, 3), AssetLimits{}), "JPEG");
}

TEST(ImageDecode, CorruptPngIsRefused) {
  std::string png = encodePng(40, 40, 4, rgbaPattern(40, 40));
  std::string garbage = png;
  size_t idat = pngChunkData(garbage, "IDAT");
  for (size_t i = idat + 10; i < idat + 60; ++i) garbage[i] = char(0x5A ^ i);
  expectInvalid(decodeTexture(garbage, AssetLimits{}), "IDAT chunk fails its CRC check");
  std::string header = png;
  header[pngChunkData(header, "IHDR") + 9] = 7;  // colour type 7 does not exist
  expectInvalid(decodeTexture(header, AssetLimits{}), "IHDR");
  // A damaged header with a matching CRC still reaches stb_image, which names the problem:
  // bit depth 3 is not a PNG bit depth.
  std::string forged = forgedPng([](std::string& png, size_t ihdr) { png[ihdr + 8] = 3; });
  expectInvalid(decodeTexture(forged, AssetLimits{}), "stb_image");
}

TEST(ImageDecode, CorruptJpegIsRefused) {
  std::string jpeg = encodeJpeg(64, 48, 3, smoothRgb(64, 48));
  // Pixel data: all-ones bits (0xFF stuffed as FF 00) are no valid Huffman code (T.81 C).
  std::string garbage = jpeg;
  size_t sos = garbage.find("\xFF\xDA");
  ASSERT_NE(sos, std::string::npos);
  size_t start = sos + 2 + 12 + 8;  // past the SOS segment of three components
  for (size_t i = start; i + 1 < start + 200 && i + 1 < garbage.size() - 2; i += 2) {
    garbage[i] = char(0xFF);
    garbage[i + 1] = 0;
  }
  expectInvalid(decodeTexture(garbage, AssetLimits{}), "JPEG");
  // Header: a frame of zero width.
  std::string header = jpeg;
  size_t sof = header.find("\xFF\xC0");
  ASSERT_NE(sof, std::string::npos);
  header[sof + 7] = 0;
  header[sof + 8] = 0;
  expectInvalid(decodeTexture(header, AssetLimits{}), "stb_image");
  // A segment length that runs past the end of the file.
  std::string length = jpeg;
  length[sof + 2] = char(0x7F);
  expectInvalid(decodeTexture(length, AssetLimits{}), "JPEG");
  // A Huffman table whose 16 code counts sum past the standard's 256 symbols (here 16 x 255):
  // Debian's stb_image would write past its 257-entry array (seen under AddressSanitizer).
  std::string huffman = jpeg;
  size_t dht = huffman.find("\xFF\xC4");
  ASSERT_NE(dht, std::string::npos);
  for (size_t i = dht + 5; i < dht + 21; ++i) huffman[i] = char(0xFF);
  expectInvalid(decodeTexture(huffman, AssetLimits{}), "Huffman");
}

TEST(BuiltinTextures, NamesAndSizes) {
  EXPECT_EQ(builtinTextureNames(), (std::vector<std::string>{"white", "checker", "uv_grid"}));
  auto white = makeBuiltinTexture("white");
  ASSERT_TRUE(white.ok());
  EXPECT_EQ(white->width, 1u);
  EXPECT_EQ(white->rgba8, (std::vector<uint8_t>{255, 255, 255, 255}));
  auto unknown = makeBuiltinTexture("marble");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::NotFound);
}

TEST(BuiltinTextures, CheckerHasEightByEightSquares) {
  auto tex = makeBuiltinTexture("checker");
  ASSERT_TRUE(tex.ok());
  ASSERT_EQ(tex->width, 256u);
  ASSERT_EQ(tex->height, 256u);
  auto at = [&](int x, int y) { return tex->rgba8[(size_t(y) * 256 + x) * 4]; };
  EXPECT_EQ(at(0, 0), 204);  // sRGB 0.8
  EXPECT_EQ(at(31, 31), 204);
  EXPECT_EQ(at(32, 0), 51);  // sRGB 0.2
  EXPECT_EQ(at(0, 32), 51);
  EXPECT_EQ(at(255, 255), 204);  // 8 squares: (7 + 7) is even
  EXPECT_EQ(at(224, 0), 51);
}

TEST(BuiltinTextures, UvGridEncodesUvWithLines) {
  auto tex = makeBuiltinTexture("uv_grid");
  ASSERT_TRUE(tex.ok());
  ASSERT_EQ(tex->width, 256u);
  auto px = [&](int x, int y) { return &tex->rgba8[(size_t(y) * 256 + x) * 4]; };
  EXPECT_EQ(px(40, 70)[0], 40);  // red = u
  EXPECT_EQ(px(40, 70)[1], 70);  // green = v, 0 at the top
  EXPECT_EQ(px(40, 70)[2], 0);
  EXPECT_EQ(px(200, 10)[0], 200);
  EXPECT_EQ(px(200, 10)[1], 10);
  for (int i : {0, 32, 64, 128, 224, 255}) {
    EXPECT_EQ(px(i, 17)[2], 255) << "vertical line at " << i;
    EXPECT_EQ(px(17, i)[2], 255) << "horizontal line at " << i;
  }
}

}  // namespace
}  // namespace brdfa
