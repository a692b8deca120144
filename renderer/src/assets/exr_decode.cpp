#include "assets/exr_decode.h"

#include <Iex.h>
#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfPartType.h>
#include <ImfTileDescription.h>
#include <ImfVersion.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace brdfa {

namespace {

// The name OpenEXR gives the file in its messages; decodeExr takes it out of them.
const char kStreamName[] = "<memory>";

// The bytes as OpenEXR's input stream: nothing is copied up front and no file is opened.
// Reading past the end throws, as OpenEXR's own file stream does; OpenEXR passes the exception
// on (sometimes with its context in front), and decodeExr turns it into the error.
class MemoryStream final : public Imf::IStream {
 public:
  explicit MemoryStream(std::string_view bytes) : Imf::IStream(kStreamName), bytes_(bytes) {}

  bool read(char c[], int n) override {
    if (n < 0 || pos_ > bytes_.size() || uint64_t(n) > bytes_.size() - pos_)
      throw Iex::InputExc("The file ends early (truncated?)");
    std::memcpy(c, bytes_.data() + pos_, size_t(n));
    pos_ += uint64_t(n);
    return pos_ < bytes_.size();
  }
  uint64_t tellg() override { return pos_; }
  void seekg(uint64_t pos) override { pos_ = pos; }  // past the end: the next read throws

 private:
  std::string_view bytes_;
  uint64_t pos_ = 0;
};

Error invalid(const std::string& message) { return makeError(ErrorCode::InvalidArgument, message); }

// OpenEXR file layout (openexr.com, "OpenEXR File Layout"): magic number and version (8 bytes);
// a header of attributes (name\0 type\0 int32 size, value) ended by an empty name, in a
// multi-part file one header per part and an empty header after the last; then each part's
// table of chunk offsets (uint64), then the chunks. Numbers are little-endian.

uint32_t littleEndian32(std::string_view bytes, size_t at) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
  return v;
}

// Whether every attribute of every header lies inside the file. OpenEXR allocates the size an
// attribute of an unknown type declares before reading it: up to 2 GiB for a damaged size.
bool headersFit(std::string_view bytes, bool multiPart) {
  size_t pos = 8;
  do {
    while (pos < bytes.size() && bytes[pos] != '\0') {  // one attribute: name, type, size, value
      for (int field = 0; field < 2; ++field) {
        size_t end = bytes.find('\0', pos);
        if (end == std::string_view::npos) return false;
        pos = end + 1;
      }
      if (bytes.size() - pos < 4 || littleEndian32(bytes, pos) > bytes.size() - pos - 4) return false;
      pos += 4 + littleEndian32(bytes, pos);
    }
    if (pos++ >= bytes.size()) return false;  // past the header's closing empty name
  } while (multiPart && pos < bytes.size() && bytes[pos] != '\0');
  return true;
}

// The headers of the parts (one in a single-part file), read before anything the size of the
// image is allocated. Throws on a damaged header.
Result<std::vector<Imf::Header>> readHeaders(std::string_view bytes, MemoryStream& stream) {
  if (bytes.size() < 8 || !Imf::isImfMagic(bytes.data()))
    return invalid("the EXR file's magic number or version field is damaged, or the file is cut short");
  int version = int(littleEndian32(bytes, 4));
  if (Imf::getVersion(version) != Imf::EXR_VERSION || !Imf::supportsFlags(Imf::getFlags(version)))
    return invalid("the EXR file's version field is damaged or names an unknown OpenEXR version");
  const bool multiPart = Imf::isMultiPart(version);
  if (!headersFit(bytes, multiPart))
    return invalid("the EXR file's header is damaged or cut short (an attribute runs past the end of the file)");
  std::vector<Imf::Header> parts;
  stream.seekg(8);
  do {
    parts.emplace_back().readFrom(stream, version);
    if (!parts.back().hasType()) parts.back().setType(Imf::isTiled(version) ? Imf::TILEDIMAGE : Imf::SCANLINEIMAGE);
  } while (multiPart && stream.tellg() < bytes.size() && bytes[stream.tellg()] != '\0');
  return parts;
}

Result<std::array<int64_t, 2>> windowSize(const Imf::Header& header) {
  const Imath::Box2i& window = header.dataWindow();
  // Inclusive bounds; a malformed window (max < min) gives a size <= 0.
  const int64_t width = int64_t(window.max.x) - window.min.x + 1;
  const int64_t height = int64_t(window.max.y) - window.min.y + 1;
  if (width <= 0 || height <= 0 || width > (1 << 24) || height > (1 << 24))
    return invalid("the EXR file's data window is empty or implausibly large");
  return std::array<int64_t, 2>{width, height};
}

int linesPerChunk(Imf::Compression compression) {
  switch (compression) {
    case Imf::ZIP_COMPRESSION:
    case Imf::PXR24_COMPRESSION: return 16;
    case Imf::PIZ_COMPRESSION:
    case Imf::B44_COMPRESSION:
    case Imf::B44A_COMPRESSION:
    case Imf::DWAA_COMPRESSION: return 32;
    case Imf::DWAB_COMPRESSION: return 256;
    default: return 1;  // NONE, RLE, ZIPS
  }
}

// The chunks of a part (for tiles, those of the full-resolution level: OpenEXR's table also
// holds the smaller levels, at most three times as many). OpenEXR allocates the part's table of
// chunk offsets from this count before reading it.
uint64_t chunkCount(const Imf::Header& part, uint64_t width, uint64_t height) {
  if (!Imf::isTiled(part.type())) {
    const uint64_t lines = linesPerChunk(part.compression());
    return (height + lines - 1) / lines;
  }
  const Imf::TileDescription& tiles = part.tileDescription();
  if (tiles.xSize == 0 || tiles.ySize == 0) return UINT64_MAX;
  return ((width + tiles.xSize - 1) / tiles.xSize) * ((height + tiles.ySize - 1) / tiles.ySize);
}

// What every part must pass before OpenEXR opens the file: a known type, a plausible data window
// and a table of chunk offsets that fits in the file.
Result<void> checkParts(std::string_view bytes, const std::vector<Imf::Header>& parts) {
  if (Imf::isDeepData(parts[0].type())) return invalid("deep EXR images (several samples per pixel) are not supported");
  uint64_t tableBytes = 0;
  for (const Imf::Header& part : parts) {
    if (!Imf::isSupportedType(part.type()))
      return invalid("the EXR file has a part of unknown type '" + part.type() + "'");
    auto size = windowSize(part);
    if (!size) return size.takeError();
    tableBytes += 8 * std::min<uint64_t>(chunkCount(part, (*size)[0], (*size)[1]), bytes.size());
  }
  if (tableBytes > bytes.size())
    return invalid(
        "the EXR file is cut short or its header is damaged (its tables of pixel chunks cannot fit "
        "in it)");
  return {};
}

std::string channelList(const Imf::ChannelList& channels) {
  std::string list;
  int count = 0;
  for (auto c = channels.begin(); c != channels.end(); ++c, ++count) {
    if (count == 12) return list + ", ...";
    list += (count ? ", " : "") + std::string(c.name());
  }
  return list.empty() ? "none" : list;
}

// The channels read into R, G and B, in order: "R", "G", "B", or only "Y" for a grey image
// (luminance without the chroma channels RY, BY). Refuses sub-sampled and integer channels.
Result<std::vector<const char*>> colourChannels(const Imf::ChannelList& channels) {
  const bool rgb = channels.findChannel("R") && channels.findChannel("G") && channels.findChannel("B");
  const bool grey = !channels.findChannel("R") && !channels.findChannel("G") && !channels.findChannel("B") &&
                    channels.findChannel("Y") && !channels.findChannel("RY") && !channels.findChannel("BY");
  if (!rgb && !grey) return invalid("the EXR file has no R, G and B channels (it has: " + channelList(channels) + ")");
  std::vector<const char*> names = grey ? std::vector<const char*>{"Y"} : std::vector<const char*>{"R", "G", "B"};
  for (const char* name : names) {
    const Imf::Channel& channel = *channels.findChannel(name);
    if (channel.xSampling != 1 || channel.ySampling != 1)
      return invalid("the EXR file's colour channels are sub-sampled (not supported)");
    if (channel.type == Imf::UINT) return invalid("the EXR file's colour channels hold integers, not radiance");
  }
  return names;
}

// The headers' checks, then the pixels of part 0's data window as float RGB.
Result<FloatImage> decodeChecked(std::string_view bytes, const ImageSizeCheck& checkSize) {
  MemoryStream stream(bytes);
  auto parts = readHeaders(bytes, stream);
  if (!parts) return parts.takeError();
  const Imf::Header& header = parts->front();
  auto size = windowSize(header);
  if (!size) return size.takeError();
  const auto [width, height] = *size;
  if (auto ok = checkSize(int(width), int(height)); !ok) return ok.takeError();
  if (auto ok = checkParts(bytes, *parts); !ok) return ok.takeError();
  if (Imf::isTiled(header.type())) {
    // OpenEXR holds a whole tile in memory: no larger than the image (or 256 x 256).
    const Imf::TileDescription& tiles = header.tileDescription();
    if (uint64_t(tiles.xSize) * tiles.ySize > std::max<uint64_t>(uint64_t(width) * height, 256 * 256))
      return invalid("the EXR file's tiles are larger than its image");
  }
  auto names = colourChannels(header.channels());
  if (!names) return names.takeError();

  stream.seekg(0);
  Imf::InputFile file(stream, /*numThreads=*/0);  // decodes in this thread, starts none
  const Imath::Box2i& window = header.dataWindow();
  FloatImage out;
  out.width = int(width);
  out.height = int(height);
  out.rgb.resize(size_t(width) * size_t(height) * 3);
  const size_t pixelStride = 3 * sizeof(float);
  Imf::FrameBuffer frame;
  for (size_t c = 0; c < names->size(); ++c)
    frame.insert((*names)[c],
                 Imf::Slice::Make(Imf::FLOAT, out.rgb.data() + c, window, pixelStride, pixelStride * size_t(width)));
  file.setFrameBuffer(frame);
  file.readPixels(window.min.y, window.max.y);
  if (names->size() == 1)  // grey
    for (size_t i = 0; i < out.rgb.size(); i += 3) out.rgb[i + 1] = out.rgb[i + 2] = out.rgb[i];
  return out;
}

// OpenEXR's message without the stream's name ("Error reading pixel data from image file
// "<memory>". Data decompression (zlib) failed.") and the trailing full stop.
std::string openExrReason(const char* what) {
  std::string reason = what;
  const std::string name = std::string(" \"") + kStreamName + "\"";
  for (size_t at; (at = reason.find(name)) != std::string::npos;) reason.erase(at, name.size());
  while (!reason.empty() && (reason.back() == '\n' || reason.back() == ' ' || reason.back() == '.')) reason.pop_back();
  return reason;
}

}  // namespace

Result<FloatImage> decodeExr(std::string_view bytes, const ImageSizeCheck& checkSize) {
  // OpenEXR reports damaged, truncated and unsupported files by throwing.
  try {
    return decodeChecked(bytes, checkSize);
  } catch (const std::exception& e) {
    return invalid("the EXR file cannot be read (OpenEXR: " + openExrReason(e.what()) + ")");
  } catch (...) {
    return invalid("the EXR file cannot be read (OpenEXR failed without a reason)");
  }
}

}  // namespace brdfa
