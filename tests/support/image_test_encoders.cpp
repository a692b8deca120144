#include "image_test_encoders.h"

#include <half.h>
#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfDeepFrameBuffer.h>
#include <ImfDeepScanLineOutputFile.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfMultiPartOutputFile.h>
#include <ImfOutputFile.h>
#include <ImfOutputPart.h>
#include <ImfPartType.h>
#include <ImfTiledOutputFile.h>
#include <ImfTiledOutputPart.h>
#include <tinyexr.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

// The renderer writes its PNGs itself (image_codec.cpp): stb_image_write is the tests' own,
// an independent encoder for the inputs.
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

namespace brdfa::testing {

namespace {

void appendBytes(void* context, void* data, int size) {
  static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
}

// OpenEXR's output stream into a string; the writers seek back to fill in the chunk table.
class StringStream final : public Imf::OStream {
 public:
  StringStream() : Imf::OStream("test.exr") {}
  void write(const char c[], int n) override {
    if (pos_ + size_t(n) > bytes.size()) bytes.resize(pos_ + size_t(n));
    std::memcpy(bytes.data() + pos_, c, size_t(n));
    pos_ += size_t(n);
  }
  uint64_t tellp() override { return pos_; }
  void seekp(uint64_t pos) override { pos_ = size_t(pos); }
  std::string bytes;

 private:
  size_t pos_ = 0;
};

// All of a scanline or tiled image (file or part) from `frame`.
template <class Scanlines>
void writeScanlines(Scanlines& out, const Imf::FrameBuffer& frame, int height) {
  out.setFrameBuffer(frame);
  out.writePixels(height);
}
template <class Tiles>
void writeTiles(Tiles& out, const Imf::FrameBuffer& frame) {
  out.setFrameBuffer(frame);
  out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
}

// A multi-part file: the image (`header`, `frame`) in part 0, a one-pixel "Z" part after it.
void writeTwoParts(StringStream& stream, Imf::Header header, const Imf::FrameBuffer& frame, int height, bool tiled) {
  header.setName("image");
  header.setType(tiled ? Imf::TILEDIMAGE : Imf::SCANLINEIMAGE);
  // The parts must agree on the display window. (Not a copy of `header` less its tiles:
  // OpenEXR 3.1's Header::erase leaks the erased attribute.)
  Imf::Header depth(header.displayWindow(), Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(0, 0)));
  depth.setName("depth");
  depth.setType(Imf::SCANLINEIMAGE);
  depth.channels().insert("Z", Imf::Channel(Imf::FLOAT));
  float z = 1.0f;
  Imf::FrameBuffer depthFrame;
  depthFrame.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(&z), sizeof(float), sizeof(float)));
  const Imf::Header headers[2] = {header, depth};
  Imf::MultiPartOutputFile out(stream, headers, 2, false, 0);
  if (tiled) {
    Imf::TiledOutputPart image(out, 0);
    writeTiles(image, frame);
  } else {
    Imf::OutputPart image(out, 0);
    writeScanlines(image, frame, height);
  }
  Imf::OutputPart depthPart(out, 1);
  writeScanlines(depthPart, depthFrame, 1);
}

// A deep scanline image, one FLOAT sample per pixel of R, G and B.
void writeDeep(StringStream& stream, int width, int height, const std::vector<float>& rgb) {
  Imf::Header header(width, height);
  header.setType(Imf::DEEPSCANLINE);
  header.compression() = Imf::ZIPS_COMPRESSION;  // deep files allow NONE, RLE, ZIPS and ZIP only
  const size_t pixels = size_t(width) * height;
  std::vector<unsigned int> counts(pixels, 1);
  std::vector<float> values = rgb;
  std::vector<float*> samples[3];
  Imf::DeepFrameBuffer frame;
  frame.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()), sizeof(unsigned int),
                                          sizeof(unsigned int) * width));
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
    for (size_t i = 0; i < pixels; ++i) samples[c].push_back(&values[i * 3 + c]);
    frame.insert(names[c], Imf::DeepSlice(Imf::FLOAT, reinterpret_cast<char*>(samples[c].data()), sizeof(float*),
                                          sizeof(float*) * width, sizeof(float)));
  }
  Imf::DeepScanLineOutputFile out(stream, header, 0);
  out.setFrameBuffer(frame);
  out.writePixels(height);
}

}  // namespace

std::string encodePng(int width, int height, int channels, const std::vector<uint8_t>& pixels) {
  std::string out;
  stbi_write_png_to_func(appendBytes, &out, width, height, channels, pixels.data(), width * channels);
  return out;
}

std::string encodeJpeg(int width, int height, int channels, const std::vector<uint8_t>& pixels, int quality) {
  std::string out;
  stbi_write_jpg_to_func(appendBytes, &out, width, height, channels, pixels.data(), quality);
  return out;
}

std::string encodeHdr(int width, int height, const std::vector<float>& rgb) {
  std::string out;
  stbi_write_hdr_to_func(appendBytes, &out, width, height, 3, rgb.data());
  return out;
}

std::string encodeExr(int width, int height, const std::vector<float>& rgb, bool half, int compression) {
  // Channels in the customary B, G, R order, one plane each.
  const size_t pixels = size_t(width) * height;
  std::vector<float> planes[3];
  for (int c = 0; c < 3; ++c) {
    planes[c].resize(pixels);
    for (size_t i = 0; i < pixels; ++i) planes[c][i] = rgb[i * 3 + (2 - c)];
  }
  float* planePointers[3] = {planes[0].data(), planes[1].data(), planes[2].data()};
  EXRImage image;
  InitEXRImage(&image);
  image.num_channels = 3;
  image.images = reinterpret_cast<unsigned char**>(planePointers);
  image.width = width;
  image.height = height;
  EXRHeader header;
  InitEXRHeader(&header);
  EXRChannelInfo channels[3] = {};
  int pixelTypes[3], requestedTypes[3];
  const char* names[3] = {"B", "G", "R"};
  for (int c = 0; c < 3; ++c) {
    std::snprintf(channels[c].name, sizeof(channels[c].name), "%s", names[c]);
    pixelTypes[c] = TINYEXR_PIXELTYPE_FLOAT;
    requestedTypes[c] = half ? TINYEXR_PIXELTYPE_HALF : TINYEXR_PIXELTYPE_FLOAT;
  }
  header.num_channels = 3;
  header.channels = channels;
  header.pixel_types = pixelTypes;
  header.requested_pixel_types = requestedTypes;
  header.compression_type = compression;
  unsigned char* memory = nullptr;
  const char* err = nullptr;
  size_t size = SaveEXRImageToMemory(&image, &header, &memory, &err);
  if (size == 0) {
    std::string reason = err ? err : "unknown";
    FreeEXRErrorMessage(err);
    throw std::runtime_error("SaveEXRImageToMemory failed: " + reason);
  }
  std::string out(reinterpret_cast<const char*>(memory), size);
  std::free(memory);
  return out;
}

std::string encodeExrWithOpenExr(int width, int height, const std::vector<float>& rgb, const OpenExrOptions& options) {
  // One plane per channel, of the channel's type: the writer does not convert.
  const size_t pixels = size_t(width) * height;
  const Imf::PixelType type = options.half ? Imf::HALF : Imf::FLOAT;
  const size_t size = options.half ? sizeof(half) : sizeof(float);
  std::vector<std::vector<char>> planes;
  auto plane = [&](auto value) {
    std::vector<char>& bytes = planes.emplace_back(pixels * size);
    for (size_t i = 0; i < pixels; ++i) {
      if (options.half)
        reinterpret_cast<half*>(bytes.data())[i] = half(value(i));
      else
        reinterpret_cast<float*>(bytes.data())[i] = value(i);
    }
    return Imf::Slice(type, bytes.data(), size, size * width);
  };
  Imf::Header header(width, height);
  header.compression() = Imf::Compression(options.compression);
  Imf::FrameBuffer frame;
  if (options.grey) {
    header.channels().insert("Y", Imf::Channel(type));
    frame.insert("Y", plane([&](size_t i) { return rgb[i * 3 + 1]; }));
  } else {
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
      header.channels().insert(names[c], Imf::Channel(type));
      frame.insert(names[c], plane([&](size_t i) { return rgb[i * 3 + c]; }));
    }
    header.channels().insert("A", Imf::Channel(type));
    frame.insert("A", plane([](size_t) { return 0.5f; }));
  }
  if (options.tiled) header.setTileDescription(Imf::TileDescription(16, 16, Imf::ONE_LEVEL));
  StringStream stream;
  if (options.deep) {
    writeDeep(stream, width, height, rgb);
  } else if (options.parts == 1) {
    if (options.tiled) {
      Imf::TiledOutputFile out(stream, header, 0);
      writeTiles(out, frame);
    } else {
      Imf::OutputFile out(stream, header, 0);
      writeScanlines(out, frame, height);
    }
  } else {
    writeTwoParts(stream, header, frame, height, options.tiled);
  }
  return stream.bytes;
}

uint8_t linearToSrgbByte(float linear) {
  float c = std::clamp(linear, 0.0f, 1.0f);
  float encoded = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(encoded * 255.0f));
}

}  // namespace brdfa::testing
