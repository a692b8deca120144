// PNG (libdeflate level 1, the Sub filter), PFM and EXR (tinyexr) encoders.
#include "brdfa/image_codec.h"

#include <libdeflate.h>
#include <tinyexr.h>  // Debian's shared libtinyexr: never define TINYEXR_IMPLEMENTATION here

#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "assets/image_structure.h"

namespace brdfa {

namespace {

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

// One chunk: length, type, data, and the CRC-32 of type and data.
void appendChunk(std::vector<uint8_t>& out, const char* type, const uint8_t* data, size_t size) {
  appendBigEndian32(out, static_cast<uint32_t>(size));
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  if (size) out.insert(out.end(), data, data + size);
  appendBigEndian32(out, libdeflate_crc32(0, out.data() + start, size + 4));
}

// A compressor per thread: libdeflate's are not thread-safe, and making one costs more than a
// small frame's compression. Level 1: a live frame is mostly sampling noise, which no level
// compresses much better, and libdeflate's level 1 is faster than zlib's.
libdeflate_compressor* threadCompressor() {
  struct Owned {
    libdeflate_compressor* c = libdeflate_alloc_compressor(1);
    ~Owned() { libdeflate_free_compressor(c); }
  };
  thread_local Owned owned;
  return owned.c;
}

}  // namespace

std::vector<uint8_t> encodePng(const uint8_t* rgba8, int width, int height,
                               const std::vector<std::pair<std::string, std::string>>& text) {
  std::vector<uint8_t> out;
  if (!rgba8 || width <= 0 || height <= 0) return out;
  libdeflate_compressor* compressor = threadCompressor();
  if (!compressor) return out;
  const size_t pixels = size_t(width) * height;
  bool opaque = true;
  for (size_t i = 0; i < pixels && opaque; ++i) opaque = rgba8[i * 4 + 3] == 255;
  // Rendered frames are opaque: RGB is a quarter less to compress, send and decode.
  const int channels = opaque ? 3 : 4;
  const size_t rowBytes = size_t(width) * channels;

  // Scanlines with the Sub filter (type 1: each byte minus the same channel of the pixel to its
  // left), the cheapest filter that still turns smooth gradients into small residuals.
  std::vector<uint8_t> filtered(size_t(height) * (rowBytes + 1));
  for (int y = 0; y < height; ++y) {
    const uint8_t* src = rgba8 + size_t(y) * width * 4;
    uint8_t* dst = filtered.data() + size_t(y) * (rowBytes + 1);
    *dst++ = 1;
    uint8_t left[4] = {0, 0, 0, 0};
    for (int x = 0; x < width; ++x, src += 4, dst += channels)
      for (int c = 0; c < channels; ++c) {
        dst[c] = static_cast<uint8_t>(src[c] - left[c]);
        left[c] = src[c];
      }
  }

  out.reserve(8 + 25 + 12 + libdeflate_zlib_compress_bound(compressor, filtered.size()) + 12);
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
  out.insert(out.end(), kSignature, kSignature + 8);
  std::vector<uint8_t> header;
  appendBigEndian32(header, static_cast<uint32_t>(width));
  appendBigEndian32(header, static_cast<uint32_t>(height));
  // 8 bits per channel; colour type 2 (RGB) or 6 (RGBA); deflate; adaptive filtering; no interlace.
  header.insert(header.end(), {8, static_cast<uint8_t>(opaque ? 2 : 6), 0, 0, 0});
  appendChunk(out, "IHDR", header.data(), header.size());
  for (const auto& [keyword, value] : text) {
    if (!validKeyword(keyword)) continue;
    std::vector<uint8_t> body(keyword.begin(), keyword.end());
    body.push_back(0);
    body.insert(body.end(), value.begin(), value.end());
    appendChunk(out, "tEXt", body.data(), body.size());
  }

  // IDAT: the zlib stream is compressed straight into place, then its length and CRC written.
  const size_t lengthAt = out.size();
  appendBigEndian32(out, 0);
  out.insert(out.end(), {'I', 'D', 'A', 'T'});
  const size_t dataAt = out.size();
  out.resize(dataAt + libdeflate_zlib_compress_bound(compressor, filtered.size()));
  const size_t compressed =
      libdeflate_zlib_compress(compressor, filtered.data(), filtered.size(), out.data() + dataAt, out.size() - dataAt);
  if (compressed == 0) return {};
  out.resize(dataAt + compressed);
  for (int i = 0; i < 4; ++i) out[lengthAt + i] = static_cast<uint8_t>(compressed >> (24 - 8 * i));
  appendBigEndian32(out, libdeflate_crc32(0, out.data() + lengthAt + 4, compressed + 4));
  appendChunk(out, "IEND", nullptr, 0);
  return out;
}

std::vector<uint8_t> encodePng(const uint8_t* rgba8, int width, int height) {
  return encodePng(rgba8, width, height, {});
}

std::string pngText(const std::vector<uint8_t>& png, const std::string& keyword) {
  if (png.size() < 8 || std::memcmp(png.data(), "\x89PNG\r\n\x1a\n", 8) != 0) return {};
  std::string text;
  walkPngChunks(std::string_view(reinterpret_cast<const char*>(png.data()), png.size()), [&](const PngChunk& c) {
    // tEXt data: keyword, a NUL, the text.
    const bool match = c.type == "tEXt" && c.data.size() > keyword.size() &&
                       c.data.substr(0, keyword.size()) == keyword && c.data[keyword.size()] == '\0';
    if (match) text = c.data.substr(keyword.size() + 1);
    return !match;
  });
  return text;
}

std::vector<uint8_t> encodePfm(const float* rgba32f, int width, int height) {
  std::vector<uint8_t> out;
  if (!rgba32f || width <= 0 || height <= 0) return out;
  const std::string header = "PF\n" + std::to_string(width) + " " + std::to_string(height) + "\n-1.0\n";
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

bool decodePfm(const std::vector<uint8_t>& bytes, int& width, int& height, std::vector<float>& rgba32f) {
  size_t pos = 0;
  std::string magic, w, h, scale;
  if (!readToken(bytes, pos, magic) || (magic != "PF" && magic != "Pf")) return false;
  if (!readToken(bytes, pos, w) || !readToken(bytes, pos, h) || !readToken(bytes, pos, scale)) return false;
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
