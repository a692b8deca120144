// PNG (stb_image_write with zlib level 1 and the Sub filter), PFM and EXR (tinyexr) encoders.
#include "brdfa/image_codec.h"

#include <tinyexr.h>  // Debian's shared libtinyexr: never define TINYEXR_IMPLEMENTATION here
#include <zlib.h>

#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "image_structure.h"

namespace {

// stb's own deflate is slow; zlib at level 1 is several times faster for live frames. stb frees
// the returned buffer with STBIW_FREE (free), so it must come from malloc.
unsigned char* brdfaZlibCompress(unsigned char* data, int dataLen, int* outLen, int /*quality*/) {
  if (!data || dataLen < 0 || !outLen) return nullptr;
  uLongf bound = compressBound(static_cast<uLong>(dataLen));
  auto* out = static_cast<unsigned char*>(std::malloc(bound));
  if (!out) return nullptr;
  if (compress2(out, &bound, data, static_cast<uLong>(dataLen), 1) != Z_OK) {
    std::free(out);
    return nullptr;
  }
  *outLen = static_cast<int>(bound);
  return out;
}

}  // namespace

#define STBIW_ZLIB_COMPRESS brdfaZlibCompress
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
#include <stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace brdfa {

namespace {

// stbi_write_force_png_filter is a global read by every encode. It is set once here, during
// static initialisation and before any thread can encode, and never written again.
const bool kForcedSubFilter = [] {
  stbi_write_force_png_filter = 1;  // PNG filter type 1 = Sub
  return true;
}();

void appendToVector(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<uint8_t>*>(context);
  const auto* bytes = static_cast<const uint8_t*>(data);
  out->insert(out->end(), bytes, bytes + size);
}

void appendFloatLE(std::vector<uint8_t>& out, float v) {
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(bits >> (8 * i)));
}

float readFloat(const uint8_t* p, bool littleEndian) {
  uint32_t bits = 0;
  for (int i = 0; i < 4; ++i) {
    const uint32_t byte = p[littleEndian ? i : 3 - i];
    bits |= byte << (8 * i);
  }
  float v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

// Reads one whitespace-delimited token of the PFM header; `pos` ends on the delimiter.
bool readToken(const std::vector<uint8_t>& b, size_t& pos, std::string& token) {
  auto space = [](uint8_t c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (pos < b.size() && space(b[pos])) ++pos;
  token.clear();
  while (pos < b.size() && !space(b[pos]) && token.size() < 64) token.push_back(char(b[pos++]));
  return !token.empty() && pos < b.size();
}

bool parseInt(const std::string& s, int& out) {
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (end != s.c_str() + s.size() || v <= 0 || v > (1 << 20)) return false;
  out = static_cast<int>(v);
  return true;
}

}  // namespace

std::vector<uint8_t> encodePng(const uint8_t* rgba8, int width, int height) {
  (void)kForcedSubFilter;
  std::vector<uint8_t> out;
  if (!rgba8 || width <= 0 || height <= 0) return out;
  const size_t pixels = size_t(width) * height;
  bool opaque = true;
  for (size_t i = 0; i < pixels && opaque; ++i) opaque = rgba8[i * 4 + 3] == 255;
  if (!opaque) {
    if (!stbi_write_png_to_func(appendToVector, &out, width, height, 4, rgba8, width * 4)) out.clear();
    return out;
  }
  // Rendered frames are opaque: RGB is a quarter less to compress, send and decode.
  std::vector<uint8_t> rgb(pixels * 3);
  for (size_t i = 0; i < pixels; ++i)
    for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = rgba8[i * 4 + c];
  if (!stbi_write_png_to_func(appendToVector, &out, width, height, 3, rgb.data(), width * 3)) out.clear();
  return out;
}

namespace {

void appendBigEndian32(std::vector<uint8_t>& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<uint8_t>(v >> shift));
}

bool validKeyword(const std::string& k) {
  if (k.empty() || k.size() > 79 || k.front() == ' ' || k.back() == ' ' || k.find("  ") != std::string::npos)
    return false;
  for (unsigned char c : k)
    if (c < 32 || (c > 126 && c < 161)) return false;
  return true;
}

constexpr size_t kPngSignatureAndHeader = 8 + 25;  // signature, then IHDR: length, type, 13 bytes, CRC

}  // namespace

std::vector<uint8_t> encodePng(const uint8_t* rgba8, int width, int height,
                               const std::vector<std::pair<std::string, std::string>>& text) {
  std::vector<uint8_t> png = encodePng(rgba8, width, height);
  if (png.size() < kPngSignatureAndHeader) return png;
  std::vector<uint8_t> chunks;
  for (const auto& [keyword, value] : text) {
    if (!validKeyword(keyword)) continue;
    std::vector<uint8_t> body{'t', 'E', 'X', 't'};
    body.insert(body.end(), keyword.begin(), keyword.end());
    body.push_back(0);
    body.insert(body.end(), value.begin(), value.end());
    appendBigEndian32(chunks, static_cast<uint32_t>(body.size() - 4));
    chunks.insert(chunks.end(), body.begin(), body.end());
    appendBigEndian32(chunks, static_cast<uint32_t>(crc32(0, body.data(), static_cast<uInt>(body.size()))));
  }
  png.insert(png.begin() + kPngSignatureAndHeader, chunks.begin(), chunks.end());
  return png;
}

std::string pngText(const std::vector<uint8_t>& png, const std::string& keyword) {
  if (png.size() < 8 || std::memcmp(png.data(), "\x89PNG\r\n\x1a\n", 8) != 0) return {};
  std::string text;
  walkPngChunks(std::string_view(reinterpret_cast<const char*>(png.data()), png.size()), [&](const PngChunk& c) {
    // tEXt data: keyword, a NUL, the text.
    const bool match = c.type == "tEXt" && c.data.size() > keyword.size() && c.data.substr(0, keyword.size()) == keyword &&
                       c.data[keyword.size()] == '\0';
    if (match) text = c.data.substr(keyword.size() + 1);
    return !match;
  });
  return text;
}

std::vector<uint8_t> encodePfm(const float* rgba32f, int width, int height) {
  std::vector<uint8_t> out;
  if (!rgba32f || width <= 0 || height <= 0) return out;
  const std::string header =
      "PF\n" + std::to_string(width) + " " + std::to_string(height) + "\n-1.0\n";
  out.reserve(header.size() + size_t(width) * height * 12);
  out.insert(out.end(), header.begin(), header.end());
  // PFM rows run bottom to top.
  for (int y = height - 1; y >= 0; --y) {
    const float* row = rgba32f + size_t(y) * width * 4;
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) appendFloatLE(out, row[x * 4 + c]);
  }
  return out;
}

std::vector<uint8_t> encodeExr(const float* rgba32f, int width, int height, bool alpha, std::string* error) {
  std::vector<uint8_t> out;
  if (!rgba32f || width <= 0 || height <= 0) {
    if (error) *error = "encodeExr: no image";
    return out;
  }
  // EXR stores channels as separate planes, listed in alphabetical order (A, B, G, R), which
  // readers such as OpenEXR expect.
  const int channels = alpha ? 4 : 3;
  const char* names[4] = {"A", "B", "G", "R"};
  const int source[4] = {3, 2, 1, 0};  // RGBA component of each listed channel
  const int first = alpha ? 0 : 1;
  const size_t pixels = size_t(width) * height;
  std::vector<std::vector<float>> planes(channels, std::vector<float>(pixels));
  std::vector<unsigned char*> planePtrs(channels);
  std::vector<EXRChannelInfo> infos(channels);
  std::vector<int> pixelTypes(channels, TINYEXR_PIXELTYPE_FLOAT);
  for (int c = 0; c < channels; ++c) {
    const int component = source[first + c];
    for (size_t i = 0; i < pixels; ++i) planes[c][i] = rgba32f[4 * i + component];
    planePtrs[c] = reinterpret_cast<unsigned char*>(planes[c].data());
    std::memset(&infos[c], 0, sizeof infos[c]);
    std::strncpy(infos[c].name, names[first + c], sizeof infos[c].name - 1);
    infos[c].pixel_type = TINYEXR_PIXELTYPE_FLOAT;
  }

  EXRImage image;
  InitEXRImage(&image);
  image.images = planePtrs.data();
  image.width = width;
  image.height = height;
  image.num_channels = channels;

  EXRHeader header;
  InitEXRHeader(&header);
  header.num_channels = channels;
  header.channels = infos.data();
  header.pixel_types = pixelTypes.data();            // what the planes hold
  header.requested_pixel_types = pixelTypes.data();  // what the file stores: float, no loss
  header.compression_type = TINYEXR_COMPRESSIONTYPE_ZIP;
  header.line_order = 0;  // increasing y: row 0 (the top) first

  unsigned char* memory = nullptr;
  const char* err = nullptr;
  const size_t size = SaveEXRImageToMemory(&image, &header, &memory, &err);
  if (size == 0 || !memory) {
    if (error) *error = err ? err : "tinyexr could not encode the image";
    if (err) FreeEXRErrorMessage(err);
    std::free(memory);
    return out;
  }
  out.assign(memory, memory + size);
  std::free(memory);  // tinyexr allocates the buffer with malloc
  return out;
}

bool decodePfm(const std::vector<uint8_t>& bytes, int& width, int& height,
               std::vector<float>& rgba32f) {
  size_t pos = 0;
  std::string magic, w, h, scale;
  if (!readToken(bytes, pos, magic) || (magic != "PF" && magic != "Pf")) return false;
  if (!readToken(bytes, pos, w) || !readToken(bytes, pos, h) || !readToken(bytes, pos, scale))
    return false;
  int wi = 0, hi = 0;
  if (!parseInt(w, wi) || !parseInt(h, hi)) return false;
  char* end = nullptr;
  const double s = std::strtod(scale.c_str(), &end);
  if (end != scale.c_str() + scale.size() || s == 0.0) return false;
  ++pos;  // exactly one whitespace byte separates the header from the raster

  const int channels = magic == "PF" ? 3 : 1;
  const size_t count = size_t(wi) * hi * channels;
  if (bytes.size() < pos || bytes.size() - pos < count * 4) return false;
  const bool littleEndian = s < 0;  // the sign of the scale gives the byte order

  rgba32f.assign(size_t(wi) * hi * 4, 1.0f);
  const uint8_t* p = bytes.data() + pos;
  for (int fileRow = 0; fileRow < hi; ++fileRow) {
    float* dst = rgba32f.data() + size_t(hi - 1 - fileRow) * wi * 4;
    for (int x = 0; x < wi; ++x) {
      for (int c = 0; c < 3; ++c) {
        const int src = channels == 3 ? c : 0;
        dst[x * 4 + c] = readFloat(p + (size_t(x) * channels + src) * 4, littleEndian);
      }
    }
    p += size_t(wi) * channels * 4;
  }
  width = wi;
  height = hi;
  return true;
}

}  // namespace brdfa
