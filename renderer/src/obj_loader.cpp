#include "obj_loader.h"

namespace brdfa {

Result<MeshData> loadObjMesh(std::string_view, const AssetLimits&, AssetInfo*) {
  return makeError(ErrorCode::Unsupported, "OBJ loading is not implemented yet");
}

}  // namespace brdfa
