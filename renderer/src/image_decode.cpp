#include "image_decode.h"

namespace brdfa {

Result<TextureData> decodeTexture(std::string_view, const AssetLimits&) {
  return makeError(ErrorCode::Unsupported, "texture decoding is not implemented yet");
}

Result<EnvironmentData> decodeEnvironment(std::string_view, const AssetLimits&, const std::string&, std::string*) {
  return makeError(ErrorCode::Unsupported, "environment decoding is not implemented yet");
}

std::vector<std::string> builtinTextureNames() { return {}; }

Result<TextureData> makeBuiltinTexture(const std::string& name) {
  return makeError(ErrorCode::NotFound, "unknown texture '" + name + "'", "texture");
}

}  // namespace brdfa
