// Wavefront OBJ meshes through tinyobjloader, from memory only: mtllib and every other file
// reference in the text are ignored, so no path from a request ever reaches the file system.
#pragma once

#include <string_view>

#include "brdfa/assets.h"

#include "assets/meshes.h"

namespace brdfa {

// Parses `bytes` as OBJ: positions, normals (smooth normals generated for corners without one,
// or with a zero one), texture coordinates, every shape merged into one mesh; polygons are
// triangulated. Vertices are the distinct (position, uv, normal) index triples the faces use.
// Texture coordinates are stored as (u, 1 - v): OBJ's v = 0 is the image's bottom row, this
// project's is the top (meshes.h). Tangent frames come from the UVs (mesh_frames.h), with a
// stable fallback when any corner lacks a UV. The mesh's conventions are those of meshes.h, but
// the winding is the file's own.
// Checks the whole text before building anything, the triangle limit of `limits` included.
// InvalidArgument with a reason (and the line, where there is one) on anything else: binary
// data, malformed numbers or indices, indices out of range, non-finite numbers, no triangles or
// too many, faces of more than 255 corners, more than 100,000 o/g groups, tinyobjloader's 't'
// statements. Fills `info` on success (may be null).
Result<MeshData> loadObjMesh(std::string_view bytes, const AssetLimits& limits, AssetInfo* info);

}  // namespace brdfa
