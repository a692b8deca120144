#include "assets/image_decode.h"

#include <stb_image.h>

#include <climits>
#include <cmath>
#include <memory>
#include <utility>

#include "assets/cross_cubemap.h"
#include "assets/equirect.h"
#include "assets/exr_decode.h"
#include "assets/image_structure.h"

namespace brdfa {

namespace {

const char* formatLabel(AssetFormat format) {
  switch (format) {
    case AssetFormat::Png: return "PNG";
    case AssetFormat::Jpeg: return "JPEG";
    case AssetFormat::Hdr: return "HDR";
    case AssetFormat::Exr: return "EXR";
    default: return "OBJ";
  }
}

Result<void> checkPixelLimit(AssetFormat format, int width, int height, const AssetLimits& limits) {
  uint64_t pixels = uint64_t(width) * uint64_t(height);
  if (pixels <= limits.maxPixels) return {};
  return makeError(ErrorCode::InvalidArgument, std::string("the ") + formatLabel(format) + " image is " +
                                                   std::to_string(width) + "x" + std::to_string(height) + " (" +
                                                   std::to_string(pixels) + " pixels); the limit is " +
                                                   std::to_string(limits.maxPixels) + " pixels");
}

Result<void> checkEquirectSize(AssetFormat format, int width, int height) {
  if (width == 2 * height) return {};
  return makeError(ErrorCode::InvalidArgument,
                   std::string("an ") + formatLabel(format) +
                       " environment must be an equirectangular map with width = 2 x height (e.g. 2048x1024); "
                       "this image is " +
                       std::to_string(width) + "x" + std::to_string(height));
}

Error stbError(AssetFormat format) {
  return makeError(
      ErrorCode::InvalidArgument,
      std::string("the ") + formatLabel(format) + " file cannot be decoded (stb_image: " + stbi_failure_reason() + ")");
}

struct StbFree {
  void operator()(void* pixels) const { stbi_image_free(pixels); }
};

// stbi_info tries every decoder in turn, so after a failure its reason is always the last
// one's "unknown image type". Loading picks the decoder by the signature and fails in the same
// header parser, early and cheaply, with the real reason ("too large", "bad SOF len", ...).
Error stbHeaderError(std::string_view bytes, AssetFormat format) {
  const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
  int width = 0, height = 0, channels = 0;
  const int size = int(bytes.size());
  void* pixels = nullptr;
  if (format == AssetFormat::Hdr)
    pixels = stbi_loadf_from_memory(data, size, &width, &height, &channels, 3);
  else
    pixels = stbi_load_from_memory(data, size, &width, &height, &channels, 4);
  // Unreachable unless the two parsers disagree; then the header is still unreadable to stbi_info.
  if (pixels) {
    stbi_image_free(pixels);
    return makeError(ErrorCode::InvalidArgument,
                     std::string("the ") + formatLabel(format) + " file's header cannot be read");
  }
  return stbError(format);
}

// The checks stb_image needs before it may read `bytes` (see image_structure.h), then its
// header: the size, handed to `checkSize` before any pixel is decoded.
Result<void> checkBeforeStb(std::string_view bytes, AssetFormat format, const ImageSizeCheck& checkSize) {
  // stb_image takes an int length.
  if (bytes.size() > size_t(INT_MAX)) return makeError(ErrorCode::InvalidArgument, "the image file is over 2 GiB");
  auto structure = format == AssetFormat::Png    ? checkPngStructure(bytes)
                   : format == AssetFormat::Jpeg ? checkJpegStructure(bytes)
                                                 : Result<void>();
  if (!structure) return structure;
  const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
  int width = 0, height = 0, channels = 0;
  if (!stbi_info_from_memory(data, int(bytes.size()), &width, &height, &channels)) return stbHeaderError(bytes, format);
  if (format == AssetFormat::Hdr) {
    if (auto ok = checkRgbeStructure(bytes, width, height); !ok) return ok;
  }
  return checkSize(width, height);
}

// PNG or JPEG to RGBA8, row 0 at the top.
Result<TextureData> decodeRgba8(std::string_view bytes, AssetFormat format, const ImageSizeCheck& checkSize) {
  if (auto ok = checkBeforeStb(bytes, format, checkSize); !ok) return ok.takeError();
  int width = 0, height = 0, channels = 0;
  std::unique_ptr<stbi_uc, StbFree> pixels(stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                                                                 int(bytes.size()), &width, &height, &channels, 4));
  if (!pixels) return stbError(format);
  TextureData texture;
  texture.width = uint32_t(width);
  texture.height = uint32_t(height);
  texture.rgba8.assign(pixels.get(), pixels.get() + size_t(width) * height * 4);
  return texture;
}

// Radiance HDR (RGBE) to linear float RGB.
Result<FloatImage> decodeHdr(std::string_view bytes, const ImageSizeCheck& checkSize) {
  if (auto ok = checkBeforeStb(bytes, AssetFormat::Hdr, checkSize); !ok) return ok.takeError();
  int width = 0, height = 0, channels = 0;
  std::unique_ptr<float, StbFree> pixels(stbi_loadf_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                                                                int(bytes.size()), &width, &height, &channels, 3));
  if (!pixels) return stbError(AssetFormat::Hdr);
  FloatImage image;
  image.width = width;
  image.height = height;
  image.rgb.assign(pixels.get(), pixels.get() + size_t(width) * height * 3);
  return image;
}

// Makes decoded radiance fit the internal cube. Non-finite values are refused: one NaN or
// infinity would spread through every estimate that samples it, and the file is broken.
// Negative values (ringing of some resampling filters, or plain errors) are not radiance and
// become 0. Radiance above the half-float range is kept: the cube is uploaded with a scale
// (packHalfCube), so a bright sun keeps its energy.
Result<void> sanitizeRadiance(FloatImage& image, AssetFormat format) {
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    float& v = image.rgb[i];
    if (!std::isfinite(v)) {
      size_t pixel = i / 3;
      return makeError(ErrorCode::InvalidArgument,
                       std::string("the ") + formatLabel(format) + " image holds a non-finite value (NaN or " +
                           "infinity) at pixel (" + std::to_string(pixel % image.width) + ", " +
                           std::to_string(pixel / image.width) + "); radiance must be finite");
    }
    v = v < 0.0f ? 0.0f : v;
  }
  return {};
}

// The size check for an environment: the pixel limit, then the layout's shape. Records the
// size in `source`.
ImageSizeCheck environmentSizeCheck(EnvironmentSource& source, const AssetLimits& limits) {
  return [&source, &limits](int width, int height) -> Result<void> {
    source.width = width;
    source.height = height;
    if (auto ok = checkPixelLimit(source.format, width, height, limits); !ok) return ok;
    if (source.layout == "cross") return checkCrossSize(width, height);
    return checkEquirectSize(source.format, width, height);
  };
}

Result<EnvironmentData> decodeEquirect(std::string_view bytes, const AssetLimits& limits, const std::string& name,
                                       EnvironmentSource& source) {
  ImageSizeCheck checkSize = environmentSizeCheck(source, limits);
  auto image = source.format == AssetFormat::Hdr ? decodeHdr(bytes, checkSize) : decodeExr(bytes, checkSize);
  if (!image) return image.takeError();
  if (auto ok = sanitizeRadiance(*image, source.format); !ok) return ok.takeError();
  return equirectToCube(std::move(image.value()), name);
}

Result<EnvironmentData> decodeCross(std::string_view bytes, const AssetLimits& limits, const std::string& name,
                                    EnvironmentSource& source) {
  auto image = decodeRgba8(bytes, source.format, environmentSizeCheck(source, limits));
  if (!image) return image.takeError();
  return crossToCube(image->rgba8.data(), int(image->width), int(image->height), name);
}

}  // namespace

Result<TextureData> decodeTexture(std::string_view bytes, const AssetLimits& limits) {
  auto format = sniffAssetFormat(bytes);
  if (format != AssetFormat::Png && format != AssetFormat::Jpeg)
    return makeError(ErrorCode::InvalidArgument, "not a PNG or JPEG image");
  return decodeRgba8(bytes, *format,
                     [&](int width, int height) { return checkPixelLimit(*format, width, height, limits); });
}

Result<EnvironmentData> decodeEnvironmentImage(std::string_view bytes, const AssetLimits& limits,
                                               const std::string& name, EnvironmentSource& source) {
  auto format = sniffAssetFormat(bytes);
  bool equirect = format == AssetFormat::Hdr || format == AssetFormat::Exr;
  bool cross = format == AssetFormat::Png || format == AssetFormat::Jpeg;
  if (!equirect && !cross) return makeError(ErrorCode::InvalidArgument, "not an HDR, EXR, PNG or JPEG image");
  source.format = *format;
  source.layout = equirect ? "equirect" : "cross";
  return equirect ? decodeEquirect(bytes, limits, name, source) : decodeCross(bytes, limits, name, source);
}

Result<EnvironmentData> decodeEnvironment(std::string_view bytes, const AssetLimits& limits, const std::string& name,
                                          std::string* layout) {
  EnvironmentSource source;
  auto env = decodeEnvironmentImage(bytes, limits, name, source);
  if (env && layout) *layout = source.layout;
  return env;
}

namespace {

TextureData makeTexture(const std::string& name, uint32_t size) {
  TextureData texture;
  texture.name = name;
  texture.width = texture.height = size;
  texture.rgba8.assign(size_t(size) * size * 4, 255);
  return texture;
}

void setPixel(TextureData& texture, uint32_t x, uint32_t y, uint8_t r, uint8_t g, uint8_t b) {
  uint8_t* p = &texture.rgba8[(size_t(y) * texture.width + x) * 4];
  p[0] = r;
  p[1] = g;
  p[2] = b;
  p[3] = 255;
}

// 8 x 8 squares of sRGB-encoded grey 0.8 (204) and 0.2 (51), light in the top-left corner.
TextureData makeChecker() {
  TextureData texture = makeTexture("checker", 256);
  for (uint32_t y = 0; y < 256; ++y)
    for (uint32_t x = 0; x < 256; ++x) {
      uint8_t grey = ((x / 32 + y / 32) % 2 == 0) ? 204 : 51;
      setPixel(texture, x, y, grey, grey, grey);
    }
  return texture;
}

// Red = u, green = v (v = 0 on the top row), blue 0: pixel x has u = (x + 0.5) / 256 at its
// centre, stored as round(255 u) = x. White one-pixel grid lines every 1/8 (32 pixels), the last
// line on the final row and column, so the grid shows how a mesh's uvs are laid out.
TextureData makeUvGrid() {
  TextureData texture = makeTexture("uv_grid", 256);
  auto onLine = [](uint32_t i) { return i % 32 == 0 || i == 255; };
  for (uint32_t y = 0; y < 256; ++y)
    for (uint32_t x = 0; x < 256; ++x) {
      if (onLine(x) || onLine(y))
        setPixel(texture, x, y, 255, 255, 255);
      else
        setPixel(texture, x, y, uint8_t(x), uint8_t(y), 0);
    }
  return texture;
}

}  // namespace

std::vector<std::string> builtinTextureNames() { return {"white", "checker", "uv_grid"}; }

Result<TextureData> makeBuiltinTexture(const std::string& name) {
  if (name == "white") return makeTexture(name, 1);
  if (name == "checker") return makeChecker();
  if (name == "uv_grid") return makeUvGrid();
  return makeError(ErrorCode::NotFound, "unknown texture '" + name + "'", "texture");
}

}  // namespace brdfa
