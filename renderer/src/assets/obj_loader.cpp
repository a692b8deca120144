#include "assets/obj_loader.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <unordered_map>
#include <vector>

#include "assets/mesh_frames.h"

namespace brdfa {

namespace {

// ---------------------------------------------------------------------------------------------
// Pre-scan. tinyobjloader lets a lot through silently: "nan" or "1,5" read as 0, a face with an
// index out of range is dropped (or, for a triangle, kept with the bad index), a face with two
// corners is skipped. So before it runs, one pass over the text checks every number and index
// and counts the triangles, which also enforces the triangle limit before anything is built.
// ---------------------------------------------------------------------------------------------

// Corners per face at most. tinyobjloader's ear clipping costs O(n^2)..O(n^3) in a face's corner
// count, so one huge polygon must not reach it; real n-gons (cylinder caps) stay well below.
constexpr size_t kMaxFaceCorners = 255;
// 'o'/'g' statements at most: tinyobjloader makes a shape (a few hundred bytes) per group with
// faces, so a file of one-triangle groups would cost far more memory than its triangles.
constexpr uint64_t kMaxGroups = 100'000;

enum Attribute { kPosition = 0, kTexCoord = 1, kNormal = 2 };
const char* const kAttributeNames[3] = {"vertex", "texture coordinate", "normal"};
const char* const kAttributePlurals[3] = {"vertices", "texture coordinates", "normals"};

struct HighestIndex {
  int64_t index = 0;  // the highest positive (1-based) index a face used
  uint64_t line = 0;  // where
};

struct ScanState {
  uint64_t line = 0;
  uint64_t defined[3] = {};  // v, vt, vn statements so far
  HighestIndex highest[3];
  uint64_t triangles = 0;
  uint64_t groups = 0;
  std::vector<std::string_view> tokens;  // the current statement's, reused line after line
  bool comment = false;                  // the current statement ends in a '#' comment
};

Error objError(std::string message) { return makeError(ErrorCode::InvalidArgument, std::move(message)); }

Error lineError(const ScanState& state, const std::string& message) {
  return objError("OBJ line " + std::to_string(state.line) + ": " + message);
}

// Short excerpt of a token for an error message, in quotes. Bytes outside printable ASCII are
// written \xNN: the message ends up in JSON, which must stay valid UTF-8 whatever the file held.
std::string quoted(std::string_view token) {
  constexpr size_t kMax = 24;
  std::string out = "'";
  for (unsigned char c : token.substr(0, kMax)) {
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  return out + (token.size() > kMax ? "...'" : "'");
}

// Bytes that never occur in OBJ text: control characters other than tab, CR and LF. Random or
// binary data hits one within a few bytes; UTF-8 (names, comments) passes.
bool binaryByte(unsigned char c) { return (c < 0x20 && c != '\t' && c != '\r' && c != '\n') || c == 0x7f; }

// Splits a statement at spaces and tabs (tinyobjloader's separators) into `out`; a token that
// starts with '#' ends it (a trailing comment; `comment` says whether there was one).
void splitTokens(std::string_view line, std::vector<std::string_view>& out, bool& comment) {
  out.clear();
  comment = false;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    size_t end = i;
    while (end < line.size() && line[end] != ' ' && line[end] != '\t') ++end;
    if (end == i) break;
    if (line[i] == '#') {
      comment = true;
      break;
    }
    out.push_back(line.substr(i, end - i));
    i = end;
  }
}

// A whole token as a number; from_chars takes no leading '+', OBJ writers sometimes do (but
// not "+-1", which tinyobjloader reads as 0).
template <class T>
bool parseWhole(std::string_view token, T& value) {
  if (!token.empty() && token[0] == '+') {
    token.remove_prefix(1);
    if (!token.empty() && (token[0] == '-' || token[0] == '+')) return false;
  }
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end && !token.empty();
}

// v x y z [w | r g b], vt u [v [w]], vn x y z: every value a finite number a float can hold.
Result<void> scanNumbers(ScanState& state, const std::vector<std::string_view>& tok, Attribute attribute) {
  static const size_t kMin[3] = {3, 1, 3}, kMax[3] = {7, 3, 3};
  static const char* const kForm[3] = {"v x y z", "vt u v", "vn x y z"};
  const size_t count = tok.size() - 1;
  if (count < kMin[attribute] || count > kMax[attribute])
    return lineError(state, std::string("a ") + kAttributeNames[attribute] + " is written '" + kForm[attribute] +
                                "', this one has " + std::to_string(count) + (count == 1 ? " number" : " numbers"));
  for (size_t i = 1; i < tok.size(); ++i) {
    double value = 0;
    if (!parseWhole(tok[i], value))
      return lineError(state, quoted(tok[i]) + " is not a number (" + kAttributeNames[attribute] + ")");
    if (!std::isfinite(value) || std::abs(value) > std::numeric_limits<float>::max())
      return lineError(state,
                       quoted(tok[i]) + " is not a finite number in float range (" + kAttributeNames[attribute] + ")");
  }
  ++state.defined[attribute];
  return {};
}

// One index of a face corner: non-zero; negative ones count back from the last definition so far.
Result<void> scanIndex(ScanState& state, std::string_view corner, std::string_view text, Attribute attribute) {
  int64_t index = 0;
  if (!parseWhole(text, index) || index == 0 || std::abs(index) > std::numeric_limits<int32_t>::max())
    return lineError(state,
                     "face corner " + quoted(corner) + " is not v, v/vt, v//vn or v/vt/vn with non-zero whole numbers");
  if (index < 0 && static_cast<uint64_t>(-index) > state.defined[attribute])
    return lineError(state, "face corner " + quoted(corner) + " counts back " + std::to_string(-index) + ", but only " +
                                std::to_string(state.defined[attribute]) + " " + kAttributePlurals[attribute] +
                                " are defined before it");
  HighestIndex& highest = state.highest[attribute];
  if (index > highest.index) highest = {index, state.line};
  return {};
}

// v, v/vt, v//vn or v/vt/vn.
Result<void> scanCorner(ScanState& state, std::string_view corner) {
  std::string_view parts[3];
  size_t count = 0;
  for (size_t start = 0;; ++count) {
    const size_t slash = corner.find('/', start);
    if (count == 3) return lineError(state, "face corner " + quoted(corner) + " has more than three parts");
    parts[count] = corner.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
    if (slash == std::string_view::npos) break;
    start = slash + 1;
  }
  ++count;
  if (auto r = scanIndex(state, corner, parts[0], kPosition); !r) return r;
  if (count >= 2 && !(count == 3 && parts[1].empty()))  // v//vn leaves the middle empty
    if (auto r = scanIndex(state, corner, parts[1], kTexCoord); !r) return r;
  if (count == 3)
    if (auto r = scanIndex(state, corner, parts[2], kNormal); !r) return r;
  return {};
}

Result<void> scanFace(ScanState& state, const std::vector<std::string_view>& tok, const AssetLimits& limits) {
  const size_t corners = tok.size() - 1;
  if (corners < 3)
    return lineError(state, "a face needs at least 3 corners, this one has " + std::to_string(corners) +
                                " (is the file cut short?)");
  if (corners > kMaxFaceCorners)
    return lineError(state, "a face has " + std::to_string(corners) + " corners; at most " +
                                std::to_string(kMaxFaceCorners) + " are supported, split it into smaller polygons");
  if (state.comment)  // tinyobjloader would read the '#' as a corner and fail
    return lineError(state, "a comment after a face is not supported; put it on a line of its own");
  for (size_t i = 1; i < tok.size(); ++i)
    if (auto r = scanCorner(state, tok[i]); !r) return r;
  state.triangles += corners - 2;  // tinyobjloader splits an n-gon into n - 2 triangles
  if (state.triangles > limits.maxTriangles)
    return lineError(state, "the mesh exceeds the limit of " + std::to_string(limits.maxTriangles) +
                                " triangles (counted after splitting polygons)");
  return {};
}

Result<void> scanStatement(ScanState& state, std::string_view line, const AssetLimits& limits) {
  splitTokens(line, state.tokens, state.comment);
  const std::vector<std::string_view>& tok = state.tokens;
  if (tok.empty()) return {};
  const std::string_view keyword = tok[0];
  if (keyword == "v") return scanNumbers(state, tok, kPosition);
  if (keyword == "vt") return scanNumbers(state, tok, kTexCoord);
  if (keyword == "vn") return scanNumbers(state, tok, kNormal);
  if (keyword == "f") return scanFace(state, tok, limits);
  // tinyobjloader's own 't' (subdivision tag) statement sizes its arrays from numbers in the
  // line (up to 3 x 8192 values per line), so a short line could claim a lot of memory.
  if (keyword == "t") return lineError(state, "'t' (subdivision tag) statements are not supported");
  if ((keyword == "o" || keyword == "g") && ++state.groups > kMaxGroups)
    return lineError(state, "more than " + std::to_string(kMaxGroups) + " 'o'/'g' groups; merge some of them");
  return {};  // other statements (s, usemtl, mtllib, l, p, ...) add nothing to the mesh
}

Result<void> checkHighestIndices(const ScanState& state) {
  for (int a = 0; a < 3; ++a) {
    const HighestIndex& h = state.highest[a];
    if (static_cast<uint64_t>(h.index) > state.defined[a])
      return objError("OBJ line " + std::to_string(h.line) + ": a face refers to " + kAttributeNames[a] + " " +
                      std::to_string(h.index) + ", but the file defines only " + std::to_string(state.defined[a]) +
                      " " + kAttributePlurals[a]);
  }
  return {};
}

// Lines end at LF, CR or CR LF, as tinyobjloader reads them.
Result<ScanState> scanObjText(std::string_view text, const AssetLimits& limits) {
  ScanState state;
  size_t pos = 0;
  while (pos < text.size()) {
    ++state.line;
    size_t end = pos;
    while (end < text.size() && text[end] != '\n' && text[end] != '\r') {
      if (binaryByte(static_cast<unsigned char>(text[end]))) {
        char hex[8];
        std::snprintf(hex, sizeof hex, "0x%02x", static_cast<unsigned char>(text[end]));
        return lineError(state, std::string("byte ") + hex +
                                    " cannot occur in OBJ text; this is not a Wavefront OBJ file (binary data?)");
      }
      ++end;
    }
    if (auto r = scanStatement(state, text.substr(pos, end - pos), limits); !r) return r.takeError();
    pos = end + (end + 1 < text.size() && text[end] == '\r' && text[end + 1] == '\n' ? 2 : 1);
  }
  if (auto r = checkHighestIndices(state); !r) return r.takeError();
  if (state.triangles == 0)
    return objError(state.defined[kPosition] == 0
                        ? "not a Wavefront OBJ mesh: no 'v' (vertex) or 'f' (face) statements found"
                        : "the OBJ has no faces ('f' lines); points and lines alone cannot be drawn");
  return state;
}

// ---------------------------------------------------------------------------------------------
// Building the mesh from tinyobjloader's result.
// ---------------------------------------------------------------------------------------------

// tinyobjloader's index triple; -1 where a corner has no normal or texture coordinate.
struct CornerKey {
  int v, vt, vn;
  bool operator==(const CornerKey& o) const { return v == o.v && vt == o.vt && vn == o.vn; }
};

struct CornerKeyHash {
  size_t operator()(const CornerKey& k) const {
    uint64_t h = static_cast<uint32_t>(k.v);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<uint32_t>(k.vt);
    h = h * 0x9E3779B97F4A7C15ull ^ static_cast<uint32_t>(k.vn);
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

struct BuiltMesh {
  MeshData mesh;
  std::vector<uint8_t> needsNormal;  // per vertex: the file gave none, or one of zero length
  bool everyCornerHasUv = true;
  uint64_t shapes = 0;
};

// tinyobjloader parses numbers its own way; the pre-scan checked the text, this checks the values.
Result<void> checkFinite(const std::vector<tinyobj::real_t>& values, const char* what) {
  for (tinyobj::real_t x : values)
    if (!std::isfinite(x)) return objError(std::string("the OBJ has a non-finite ") + what);
  return {};
}

// Defence in depth behind the pre-scan: an index tinyobjloader resolved outside its arrays.
bool inRange(int index, size_t size, bool optional) {
  return (optional && index == -1) || (index >= 0 && static_cast<size_t>(index) < size);
}

class ObjMeshBuilder {
 public:
  explicit ObjMeshBuilder(const tinyobj::attrib_t& attrib) : attrib_(attrib) {}

  Result<void> addShape(const tinyobj::shape_t& shape) {
    if (shape.mesh.indices.empty()) return {};  // a group of lines or points only
    ++out_.shapes;
    for (const tinyobj::index_t& corner : shape.mesh.indices) {
      if (!inRange(corner.vertex_index, attrib_.vertices.size() / 3, false) ||
          !inRange(corner.texcoord_index, attrib_.texcoords.size() / 2, true) ||
          !inRange(corner.normal_index, attrib_.normals.size() / 3, true))
        return objError("a face in shape " + quoted(shape.name) + " refers to a vertex that does not exist");
      auto vertex = vertexFor({corner.vertex_index, corner.texcoord_index, corner.normal_index});
      if (!vertex) return vertex.takeError();
      out_.mesh.indices.push_back(vertex.value());
    }
    return {};
  }

  BuiltMesh take() { return std::move(out_); }

 private:
  Result<uint32_t> vertexFor(const CornerKey& key) {
    auto [it, added] = index_.emplace(key, static_cast<uint32_t>(out_.mesh.vertices.size()));
    if (!added) return it->second;
    // Guard: 32-bit indices. Unreachable under the default limits; the renderer loads stored
    // files with no limit.
    if (out_.mesh.vertices.size() >= std::numeric_limits<uint32_t>::max())
      return objError("the OBJ has more distinct vertices than 32-bit indices can address");
    out_.mesh.vertices.push_back(makeVertex(key));
    return it->second;
  }

  Vertex makeVertex(const CornerKey& key) {
    Vertex v{};
    for (int k = 0; k < 3; ++k) v.position[k] = attrib_.vertices[3 * size_t(key.v) + k];
    bool hasNormal = false;
    if (key.vn >= 0) {
      const float* n = &attrib_.normals[3 * size_t(key.vn)];
      const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      hasNormal = len > 0.0f && std::isfinite(len);  // a zero normal in the file is replaced
      for (int k = 0; hasNormal && k < 3; ++k) v.normal[k] = n[k] / len;
    }
    out_.needsNormal.push_back(hasNormal ? 0 : 1);
    if (key.vt >= 0) {
      // OBJ puts v = 0 at the bottom of the image; here v = 0 is the first (top) row, as the
      // textures are stored and Vulkan samples them. Hence v' = 1 - v.
      v.texCoord[0] = attrib_.texcoords[2 * size_t(key.vt)];
      v.texCoord[1] = 1.0f - attrib_.texcoords[2 * size_t(key.vt) + 1];
    } else {
      out_.everyCornerHasUv = false;
    }
    return v;
  }

  const tinyobj::attrib_t& attrib_;
  std::unordered_map<CornerKey, uint32_t, CornerKeyHash> index_;
  BuiltMesh out_;
};

// Smooth normals for the vertices that have none; the file's own normals stay as they are.
bool fillMissingNormals(BuiltMesh& built) {
  size_t missing = 0;
  for (uint8_t m : built.needsNormal) missing += m;
  if (missing == 0) return false;
  if (missing == built.needsNormal.size()) {
    generateSmoothNormals(built.mesh);
    return true;
  }
  MeshData smooth = built.mesh;
  generateSmoothNormals(smooth);
  for (size_t i = 0; i < built.needsNormal.size(); ++i)
    if (built.needsNormal[i])
      std::copy(smooth.vertices[i].normal, smooth.vertices[i].normal + 3, built.mesh.vertices[i].normal);
  return true;
}

Result<tinyobj::ObjReader> parseWithTinyObj(std::string_view text) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;  // not used; saves a float triple per vertex
  tinyobj::ObjReader reader;
  // The MTL text is empty: ParseFromString never opens a file, so 'mtllib' names in a request
  // (even "../../etc/passwd") are not read, and materials stay unknown (they are not used).
  if (!reader.ParseFromString(std::string(text), std::string(), config)) {
    std::string why = reader.Error();
    while (!why.empty() && (why.back() == '\n' || why.back() == '.')) why.pop_back();
    return objError("OBJ could not be parsed: " + (why.empty() ? std::string("unknown reason") : why));
  }
  return reader;
}

}  // namespace

Result<MeshData> loadObjMesh(std::string_view bytes, const AssetLimits& limits, AssetInfo* info) {
  // A UTF-8 byte order mark would hide the first statement from tinyobjloader.
  if (bytes.substr(0, 3) == "\xEF\xBB\xBF") bytes.remove_prefix(3);
  auto scan = scanObjText(bytes, limits);
  if (!scan) return scan.takeError();

  auto reader = parseWithTinyObj(bytes);
  if (!reader) return reader.takeError();
  const tinyobj::attrib_t& attrib = reader->GetAttrib();
  for (auto check : {checkFinite(attrib.vertices, "vertex position"), checkFinite(attrib.normals, "normal"),
                     checkFinite(attrib.texcoords, "texture coordinate")})
    if (!check) return check.takeError();

  ObjMeshBuilder builder(attrib);
  for (const tinyobj::shape_t& shape : reader->GetShapes())
    if (auto r = builder.addShape(shape); !r) return r.takeError();
  BuiltMesh built = builder.take();
  const uint64_t triangles = built.mesh.indices.size() / 3;
  // tinyobjloader may still drop a polygon its ear clipping cannot split.
  if (triangles == 0) return objError("the OBJ has no faces that could be split into triangles");
  if (triangles > limits.maxTriangles)
    return objError("the mesh exceeds the limit of " + std::to_string(limits.maxTriangles) + " triangles");

  const bool generatedNormals = fillMissingNormals(built);
  generateTangents(built.mesh, built.everyCornerHasUv);
  if (info) {
    info->kind = AssetKind::Mesh;
    info->format = AssetFormat::Obj;
    info->vertices = built.mesh.vertices.size();
    info->triangles = triangles;
    info->shapes = built.shapes;
    info->generatedNormals = generatedNormals;
    info->generatedTangents = !built.everyCornerHasUv;
  }
  built.mesh.name = "obj";
  return std::move(built.mesh);
}

}  // namespace brdfa
