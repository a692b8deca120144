// Wavefront OBJ meshes through tinyobjloader, from memory only: mtllib and every other file
// reference in the text are ignored, so no path from a request ever reaches the file system.
#pragma once

#include <string_view>

#include "brdfa/assets.h"
#include "meshes.h"

namespace brdfa {

// Parses `bytes` as OBJ: positions, normals (smooth normals generated when the file has none),
// texture coordinates, every shape merged into one mesh; polygons are triangulated. Tangent
// frames come from the UVs (mesh_frames.h), with a stable fallback without UVs. Checks the
// triangle limit of `limits`. InvalidArgument with a reason on malformed text, indices out of
// range, non-finite numbers, no triangles or too many. Fills `info` (may be null).
Result<MeshData> loadObjMesh(std::string_view bytes, const AssetLimits& limits, AssetInfo* info);

}  // namespace brdfa
