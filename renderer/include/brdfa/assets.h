// Scene assets the renderer can load from files: meshes, textures and environments.
// No Vulkan and no HTTP here: the server validates uploads with inspectAsset() before it
// stores them, then names the stored file to the renderer with Renderer::registerAsset().
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "brdfa/result.h"

namespace brdfa {

enum class AssetKind { Mesh, Texture, Environment, Measured };
const char* assetKindName(AssetKind kind);                       // "mesh" | "texture" | "environment" | "measured"
bool assetKindFromName(std::string_view name, AssetKind& kind);  // false if unknown

// File formats, told apart by content (magic numbers, OBJ statements), never by a file name.
enum class AssetFormat { Obj, Png, Jpeg, Hdr, Exr, Merl };
const char* assetFormatName(AssetFormat format);  // "obj" | "png" | "jpeg" | "hdr" | "exr" | "merl"
// The format `bytes` hold, or nullopt when they are none of them. OBJ is recognised as text
// whose first statement is an OBJ statement (v, vn, vt, f, o, g, s, mtllib, usemtl, l, p, #);
// a MERL table by its header (90, 90, 180).
std::optional<AssetFormat> sniffAssetFormat(std::string_view bytes);

// Upper bounds on what one asset may hold; each is checked before the data is used, and the
// pixel bound before an image is decoded (from its header).
struct AssetLimits {
  uint64_t maxBytes = 64ull << 20;      // encoded file size
  uint64_t maxTriangles = 2'000'000;    // after polygons are split into triangles
  uint64_t maxPixels = 4096ull * 4096;  // width * height of a texture or environment image
};

// What inspectAsset found. Meshes fill vertices/triangles/shapes; images width/height.
struct AssetInfo {
  AssetKind kind = AssetKind::Mesh;
  AssetFormat format = AssetFormat::Obj;
  std::string layout;     // environments: "equirect" (HDR, EXR) | "cross" (PNG, JPEG)
  uint64_t vertices = 0;  // after de-duplication of (position, normal, uv) triples
  uint64_t triangles = 0;
  uint64_t shapes = 0;             // OBJ o/g groups holding faces
  bool generatedNormals = false;   // the OBJ had none: smooth normals were computed
  bool generatedTangents = false;  // no texture coordinates: a stable fallback frame was used
  int width = 0, height = 0;
  uint64_t measuredBins = 0;  // measured tables: bins that hold data (of kMerlBins)
};

// Decodes `bytes` completely as an asset of `kind` and checks it against `limits`:
//   Mesh:        OBJ (positions, optional normals and uvs, any number of shapes);
//   Texture:     PNG or JPEG;
//   Environment: equirectangular HDR or EXR (width = 2 height), or a PNG/JPEG horizontal cross
//                cube map (width / 4 = height / 3, square faces);
//   Measured:    a MERL table (brdfa/measured.h: readMerl's checks).
// Returns InvalidArgument with a reason a user can act on for anything else: a format that is
// not one of `kind`'s, a truncated or corrupt file, no triangles, NaN/Inf data, limits exceeded.
// Thread-safe; needs no device.
Result<AssetInfo> inspectAsset(std::string_view bytes, AssetKind kind, const AssetLimits& limits);

}  // namespace brdfa
