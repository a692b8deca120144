// Images decoded from files: textures (PNG, JPEG through stb_image) and environments
// (equirectangular HDR through stb_image, EXR through tinyexr, LDR horizontal-cross cube maps),
// all environments converted to the one internal form, an RGBA16F cube map.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "brdfa/assets.h"
#include "environment_maps.h"

namespace brdfa {

struct TextureData {
  std::string name;
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgba8;  // row 0 at the top; stored as encoded (sRGB decode is the sampler's)
};

// PNG or JPEG to RGBA8. Checks the pixel limit from the header before decoding.
// InvalidArgument with a reason otherwise.
Result<TextureData> decodeTexture(std::string_view bytes, const AssetLimits& limits);

// An environment image to the internal cube map: HDR or EXR equirectangular (width = 2 height,
// +Y up, the image centre looking down -Z), or a PNG/JPEG horizontal cross (sRGB, converted to
// linear). Sets *layout to "equirect" or "cross" when not null. InvalidArgument with a reason
// otherwise (wrong aspect, non-finite or negative radiance, limits).
Result<EnvironmentData> decodeEnvironment(std::string_view bytes, const AssetLimits& limits, const std::string& name,
                                          std::string* layout);

// Built-in textures made by the project.
std::vector<std::string> builtinTextureNames();
Result<TextureData> makeBuiltinTexture(const std::string& name);  // NotFound when unknown

}  // namespace brdfa
