#include "assets/image_structure.h"

#include <zlib.h>

#include <cctype>
#include <cstdint>
#include <string>

namespace brdfa {

namespace {

uint32_t readBigEndian32(const unsigned char* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}

Error corrupt(const char* format, const std::string& what) {
  return makeError(ErrorCode::InvalidArgument, std::string("the ") + format + " file is damaged: " + what);
}

// A chunk type as text when it is four letters (as valid ones are), else as "unknown".
std::string chunkName(std::string_view type) {
  for (char c : type)
    if (!std::isalpha(static_cast<unsigned char>(c))) return "an unknown";
  return "the " + std::string(type);
}

}  // namespace

PngWalk walkPngChunks(std::string_view bytes, const std::function<bool(const PngChunk&)>& visit) {
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const size_t size = bytes.size();
  for (size_t pos = 8; pos < size;) {
    // Each chunk: 4-byte length, 4-byte type, data, 4-byte CRC of type and data.
    if (size - pos < 12) return {PngWalk::End::TruncatedHeader, {}};
    const uint32_t length = readBigEndian32(data + pos);
    const std::string_view type = bytes.substr(pos + 4, 4);
    if (length > size - pos - 12) return {PngWalk::End::TruncatedChunk, type};
    const PngChunk chunk{type, bytes.substr(pos + 8, length), readBigEndian32(data + pos + 8 + length)};
    if (!visit(chunk)) return {PngWalk::End::Stopped, type};
    if (type == "IEND") return {PngWalk::End::Iend, {}};
    pos += 12 + size_t(length);
  }
  return {PngWalk::End::NoIend, {}};
}

Result<void> checkPngStructure(std::string_view bytes) {
  // The signature was checked by the caller.
  std::string_view badCrc;
  const PngWalk walk = walkPngChunks(bytes, [&](const PngChunk& c) {
    const auto* typeAndData = reinterpret_cast<const unsigned char*>(c.type.data());
    const auto actual = static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0), typeAndData, uInt(4 + c.data.size())));
    if (actual == c.storedCrc) return true;
    badCrc = c.type;
    return false;
  });
  switch (walk.end) {
    case PngWalk::End::Iend: return {};
    case PngWalk::End::Stopped: return corrupt("PNG", chunkName(badCrc) + " chunk fails its CRC check");
    case PngWalk::End::TruncatedHeader: return corrupt("PNG", "it ends inside a chunk header (truncated?)");
    case PngWalk::End::TruncatedChunk:
      return corrupt("PNG", "it ends inside " + chunkName(walk.type) + " chunk (truncated?)");
    case PngWalk::End::NoIend: break;
  }
  return corrupt("PNG", "it ends before its IEND chunk (truncated?)");
}

namespace {

// Past the entropy-coded data of a scan that starts at `pos`: up to the next marker other
// than a stuffed 0xFF00 or a restart marker RSTn. Returns the marker's position, or
// bytes.size() when the data runs out first.
size_t skipEntropyCodedData(const unsigned char* data, size_t size, size_t pos) {
  while (pos + 1 < size) {
    if (data[pos] != 0xFF) {
      ++pos;
      continue;
    }
    unsigned char next = data[pos + 1];
    if (next == 0x00 || (next >= 0xD0 && next <= 0xD7))
      pos += 2;  // stuffed byte or RSTn
    else if (next == 0xFF)
      ++pos;  // fill byte before a marker
    else
      return pos;
  }
  return size;
}

// A DHT segment's tables (`data` after the length field, `length` bytes): each is a class/id
// byte, 16 code counts and that many symbols. stb_image (Debian's 2.27) copies a table's code
// lengths into a 257-entry array without checking that the counts sum to at most 256: a
// crafted table overflows it (a heap write). The JPEG standard allows 256 symbols per table.
bool validHuffmanTables(const unsigned char* data, size_t length) {
  size_t pos = 0;
  while (pos < length) {
    if (length - pos < 17) return false;
    const unsigned tableClass = data[pos] >> 4, tableId = data[pos] & 15;
    if (tableClass > 1 || tableId > 3) return false;
    size_t symbols = 0;
    for (size_t i = 1; i <= 16; ++i) symbols += data[pos + i];
    if (symbols > 256 || symbols > length - pos - 17) return false;
    pos += 17 + symbols;
  }
  return true;
}

}  // namespace

Result<void> checkJpegStructure(std::string_view bytes) {
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const size_t size = bytes.size();
  size_t pos = 2;  // after SOI (FF D8), which the caller has checked
  while (pos < size) {
    if (data[pos] != 0xFF) return corrupt("JPEG", "no marker where one belongs at byte " + std::to_string(pos));
    while (pos < size && data[pos] == 0xFF) ++pos;  // a marker may be preceded by fill bytes
    if (pos >= size) break;
    unsigned char marker = data[pos++];
    if (marker == 0xD9) return {};                                       // EOI
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // TEM, RSTn: no length
    // Every other marker starts a segment whose 2-byte length counts itself.
    if (size - pos < 2) break;
    size_t length = (size_t(data[pos]) << 8) | data[pos + 1];
    if (length < 2) return corrupt("JPEG", "a segment has an impossible length at byte " + std::to_string(pos));
    if (length > size - pos) break;
    if (marker == 0xC4 && !validHuffmanTables(data + pos + 2, length - 2))
      return corrupt("JPEG", "a Huffman table (DHT) at byte " + std::to_string(pos) + " is malformed");
    pos += length;
    if (marker == 0xDA) pos = skipEntropyCodedData(data, size, pos);  // SOS: the scan's data follows
  }
  return corrupt("JPEG", "it ends before its end-of-image marker (truncated?)");
}

namespace {

// Position just past the header and resolution line of a Radiance file: the header ends at
// its first empty line, the next line is the resolution ("-Y h +X w"). npos when missing.
size_t rgbeDataStart(std::string_view bytes) {
  size_t headerEnd = bytes.find("\n\n");
  if (headerEnd == std::string_view::npos) return std::string_view::npos;
  size_t resolutionEnd = bytes.find('\n', headerEnd + 2);
  return resolutionEnd == std::string_view::npos ? resolutionEnd : resolutionEnd + 1;
}

constexpr const char* kRgbeTruncated = "it ends inside its pixel data (truncated?)";

// One component (of 4) of a run-length scanline: runs (count > 128: one byte repeated
// count - 128 times) and dumps (count <= 128: that many literal bytes) filling `width`
// values. Advances `pos`; returns what is wrong, or nullptr when the component is whole.
const char* walkRleComponent(const unsigned char* data, size_t size, size_t& pos, int width) {
  int filled = 0;
  while (filled < width) {
    if (pos >= size) return kRgbeTruncated;
    int count = data[pos++];
    bool run = count > 128;
    if (run) count -= 128;
    size_t payload = run ? 1 : size_t(count);
    if (count > width - filled) return "a run-length scanline overruns its width";
    if (payload > size - pos) return kRgbeTruncated;
    pos += payload;
    filled += count;
  }
  return nullptr;
}

}  // namespace

Result<void> checkRgbeStructure(std::string_view bytes, int width, int height) {
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const size_t size = bytes.size();
  size_t pos = rgbeDataStart(bytes);
  if (pos == std::string_view::npos) return corrupt("HDR", "its header has no resolution line");
  const uint64_t flatBytes = uint64_t(4) * uint64_t(width) * uint64_t(height);
  // stb_image reads flat (uncompressed) RGBE when the width cannot be run-length encoded.
  if (width < 8 || width >= 32768) {
    if (size - pos < flatBytes) return corrupt("HDR", kRgbeTruncated);
    return {};
  }
  for (int y = 0; y < height; ++y) {
    if (size - pos < 4) return corrupt("HDR", kRgbeTruncated);
    const unsigned char* line = data + pos;
    bool rle = line[0] == 2 && line[1] == 2 && (line[2] & 0x80) == 0;
    // A scanline that is not run-length encoded makes stb_image restart and read the whole
    // image as flat pixels from here: width x height of them.
    if (!rle) {
      if (size - pos < flatBytes) return corrupt("HDR", kRgbeTruncated);
      return {};
    }
    if (((int(line[2]) << 8) | line[3]) != width) return corrupt("HDR", "a scanline's length differs from the width");
    pos += 4;
    for (int component = 0; component < 4; ++component)
      if (const char* damage = walkRleComponent(data, size, pos, width)) return corrupt("HDR", damage);
  }
  return {};
}

}  // namespace brdfa
