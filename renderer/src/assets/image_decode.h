// Images decoded from files: textures (PNG, JPEG through stb_image) and environments
// (equirectangular HDR through stb_image, EXR through OpenEXR, LDR horizontal-cross cube maps),
// all environments converted to the one internal form, an RGBA16F cube map. Before stb_image
// reads a file its structure is checked (image_structure.h): stb_image alone accepts truncated
// JPEGs, can hang on truncated HDRs and ignores PNG checksums. All functions are thread-safe.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "brdfa/assets.h"

#include "assets/environment_maps.h"

namespace brdfa {

struct TextureData {
  std::string name;
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgba8;  // row 0 at the top; stored as encoded (sRGB decode is the sampler's)
};

// PNG or JPEG to RGBA8. Checks the pixel limit from the header before decoding.
// InvalidArgument with a reason otherwise: "not a PNG or JPEG image", the size against the
// limit, or the format and what is wrong (a failed CRC, a missing end, stb_image's reason).
Result<TextureData> decodeTexture(std::string_view bytes, const AssetLimits& limits);

// An environment image to the internal cube map: HDR or EXR equirectangular (width = 2 height,
// +Y up, the image centre looking down -Z; the exact mapping is in equirect.h), or a PNG/JPEG
// horizontal cross (sRGB, converted to linear; layout and orientation in cross_cubemap.h).
// Checks the pixel limit and the aspect from the header before decoding. Sets *layout to
// "equirect" or "cross" when not null. InvalidArgument with a reason otherwise (wrong aspect,
// truncated or damaged file, NaN or infinite radiance, limits). Negative radiance is clamped
// to 0; radiance above the half-float range is kept (packHalfCube scales the upload).
Result<EnvironmentData> decodeEnvironment(std::string_view bytes, const AssetLimits& limits, const std::string& name,
                                          std::string* layout);

// What decodeEnvironmentImage read: the file's format and layout and the source image's size.
struct EnvironmentSource {
  AssetFormat format = AssetFormat::Hdr;
  std::string layout;  // "equirect" | "cross"
  int width = 0, height = 0;
};

// decodeEnvironment, also telling what the source was (for inspectAsset).
Result<EnvironmentData> decodeEnvironmentImage(std::string_view bytes, const AssetLimits& limits,
                                               const std::string& name, EnvironmentSource& source);

// Built-in textures made by the project: "white" (1x1), "checker" (256x256, 8x8 squares of
// sRGB grey 0.8 and 0.2) and "uv_grid" (256x256, red = u, green = v with v = 0 on the top row,
// white grid lines every 1/8).
std::vector<std::string> builtinTextureNames();
Result<TextureData> makeBuiltinTexture(const std::string& name);  // NotFound when unknown

}  // namespace brdfa
