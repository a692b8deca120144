#include "brdfa/assets.h"

namespace brdfa {

const char* assetKindName(AssetKind kind) {
  switch (kind) {
    case AssetKind::Texture: return "texture";
    case AssetKind::Environment: return "environment";
    default: return "mesh";
  }
}

bool assetKindFromName(std::string_view name, AssetKind& kind) {
  for (AssetKind k : {AssetKind::Mesh, AssetKind::Texture, AssetKind::Environment})
    if (name == assetKindName(k)) {
      kind = k;
      return true;
    }
  return false;
}

const char* assetFormatName(AssetFormat format) {
  switch (format) {
    case AssetFormat::Png: return "png";
    case AssetFormat::Jpeg: return "jpeg";
    case AssetFormat::Hdr: return "hdr";
    case AssetFormat::Exr: return "exr";
    default: return "obj";
  }
}

std::optional<AssetFormat> sniffAssetFormat(std::string_view) { return std::nullopt; }

Result<AssetInfo> inspectAsset(std::string_view, AssetKind, const AssetLimits&) {
  return makeError(ErrorCode::Unsupported, "asset inspection is not implemented yet");
}

}  // namespace brdfa
