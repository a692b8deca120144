// OBJ meshes from memory (renderer/src/assets/obj_loader.h): what loads, what the loader fills in
// (normals, tangents, V flip, merged shapes, triangulated polygons), and what it refuses, each
// refusal with a message that says what is wrong.
#include <gtest/gtest.h>

#include <glm/glm.hpp>

#include <random>
#include <string>

#include "assets/mesh_frames.h"
#include "assets/obj_loader.h"

namespace brdfa {
namespace {

glm::vec3 position(const Vertex& v) { return {v.position[0], v.position[1], v.position[2]}; }
glm::vec3 normal(const Vertex& v) { return {v.normal[0], v.normal[1], v.normal[2]}; }
glm::vec3 tangent(const Vertex& v) { return {v.tangent[0], v.tangent[1], v.tangent[2]}; }

// A 2x2x2 cube: one normal per face, the four corners of the unit UV square on every face.
const char* const kCubePositions =
    "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n"
    "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n";
const char* const kCubeTexCoords = "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
const char* const kCubeNormals = "vn 0 0 -1\nvn 0 0 1\nvn 0 -1 0\nvn 0 1 0\nvn -1 0 0\nvn 1 0 0\n";
// Counter-clockwise seen from outside.
const char* const kCubeFacesFull =
    "f 2/1/1 1/2/1 4/3/1 3/4/1\n"
    "f 5/1/2 6/2/2 7/3/2 8/4/2\n"
    "f 1/1/3 2/2/3 6/3/3 5/4/3\n"
    "f 8/1/4 7/2/4 3/3/4 4/4/4\n"
    "f 1/1/5 5/2/5 8/3/5 4/4/5\n"
    "f 6/1/6 2/2/6 3/3/6 7/4/6\n";
const char* const kCubeFacesPositionsOnly = "f 2 1 4 3\nf 5 6 7 8\nf 1 2 6 5\nf 8 7 3 4\nf 1 5 8 4\nf 6 2 3 7\n";

std::string cubeObj() { return std::string(kCubePositions) + kCubeTexCoords + kCubeNormals + kCubeFacesFull; }

Result<MeshData> load(const std::string& text, AssetInfo* info = nullptr, AssetLimits limits = {}) {
  return loadObjMesh(text, limits, info);
}

MeshData loadOk(const std::string& text, AssetInfo* info = nullptr) {
  auto mesh = load(text, info);
  EXPECT_TRUE(mesh.ok()) << (mesh.ok() ? "" : mesh.error().message);
  return mesh.ok() ? std::move(mesh).value() : MeshData{};
}

// The load fails with InvalidArgument and a message holding every one of `words`.
void expectRefused(const std::string& text, std::initializer_list<const char*> words, AssetLimits limits = {}) {
  auto mesh = load(text, nullptr, limits);
  ASSERT_FALSE(mesh.ok()) << "accepted: " << text.substr(0, 80);
  EXPECT_EQ(mesh.error().code, ErrorCode::InvalidArgument);
  for (const char* word : words)
    EXPECT_NE(mesh.error().message.find(word), std::string::npos)
        << "'" << word << "' missing from: " << mesh.error().message;
}

void expectUnitOrthogonalFrames(const MeshData& m) {
  for (const Vertex& v : m.vertices) {
    ASSERT_NEAR(glm::length(normal(v)), 1.0f, 1e-5f);
    ASSERT_NEAR(glm::length(tangent(v)), 1.0f, 1e-5f);
    ASSERT_NEAR(glm::dot(normal(v), tangent(v)), 0.0f, 1e-5f);
    ASSERT_TRUE(v.tangent[3] == 1.0f || v.tangent[3] == -1.0f);
  }
}

double totalArea(const MeshData& m) {
  double area = 0;
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const glm::vec3 p0 = position(m.vertices[m.indices[t]]);
    area += 0.5 * glm::length(glm::cross(position(m.vertices[m.indices[t + 1]]) - p0,
                                         position(m.vertices[m.indices[t + 2]]) - p0));
  }
  return area;
}

TEST(ObjLoader, CubeWithNormalsAndUvs) {
  AssetInfo info;
  info.generatedNormals = info.generatedTangents = true;  // must be cleared
  const MeshData m = loadOk(cubeObj(), &info);
  EXPECT_EQ(info.kind, AssetKind::Mesh);
  EXPECT_EQ(info.format, AssetFormat::Obj);
  EXPECT_EQ(info.vertices, 24u);  // distinct (position, uv, normal) triples
  EXPECT_EQ(info.triangles, 12u);
  EXPECT_EQ(info.shapes, 1u);
  EXPECT_FALSE(info.generatedNormals);
  EXPECT_FALSE(info.generatedTangents);
  EXPECT_EQ(m.vertices.size(), 24u);
  EXPECT_EQ(m.indices.size(), 36u);
  expectUnitOrthogonalFrames(m);
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    const Vertex& a = m.vertices[m.indices[t]];
    const glm::vec3 g = glm::cross(position(m.vertices[m.indices[t + 1]]) - position(a),
                                   position(m.vertices[m.indices[t + 2]]) - position(a));
    EXPECT_GT(glm::dot(g, normal(a)), 0.0f);                  // file normals kept, winding outward
    EXPECT_FLOAT_EQ(glm::dot(position(a), normal(a)), 1.0f);  // the file's face normals
  }
}

TEST(ObjLoader, FlipsVSoTheImageTopIsVZero) {
  const MeshData m = loadOk("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 0.25\nf 1/1 2/2 3/3\n");
  ASSERT_EQ(m.vertices.size(), 3u);
  EXPECT_EQ(m.vertices[0].texCoord[1], 1.0f);  // OBJ v = 0 is the image's bottom row
  EXPECT_EQ(m.vertices[2].texCoord[1], 0.75f);
  EXPECT_EQ(m.vertices[1].texCoord[0], 1.0f);
  // dP/du = +X; v' grows toward -Y, so B = w cross(+Z, +X) = w (+Y) must be -Y: w = -1.
  EXPECT_NEAR(m.vertices[0].tangent[0], 1.0f, 1e-6f);
  EXPECT_EQ(m.vertices[0].tangent[3], -1.0f);
}

TEST(ObjLoader, WithoutNormalsGetsSmoothOutwardNormals) {
  AssetInfo info;
  const MeshData m = loadOk(std::string(kCubePositions) + kCubeFacesPositionsOnly, &info);
  EXPECT_TRUE(info.generatedNormals);
  EXPECT_EQ(m.vertices.size(), 8u);
  for (const Vertex& v : m.vertices) {
    EXPECT_NEAR(glm::length(normal(v)), 1.0f, 1e-5f);
    // Smooth corner normals of a cube point along the diagonal.
    EXPECT_NEAR(glm::dot(normal(v), glm::normalize(position(v))), 1.0f, 1e-5f);
  }
}

TEST(ObjLoader, ZeroNormalsInTheFileAreReplaced) {
  AssetInfo info;
  const MeshData m = loadOk("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn 0 0 2\nf 1//1 2//2 3//2\n", &info);
  EXPECT_TRUE(info.generatedNormals);
  for (const Vertex& v : m.vertices) EXPECT_EQ(normal(v), glm::vec3(0, 0, 1));  // generated, and normalized
}

TEST(ObjLoader, WithoutUvsTangentsAreTheStableFallback) {
  AssetInfo info;
  const MeshData m = loadOk(std::string(kCubePositions) + kCubeFacesPositionsOnly, &info);
  EXPECT_TRUE(info.generatedTangents);
  expectUnitOrthogonalFrames(m);
  for (const Vertex& v : m.vertices) {
    glm::vec3 t, b;
    orthonormalBasis(normal(v), t, b);
    EXPECT_EQ(tangent(v), t);
    EXPECT_EQ(v.tangent[3], 1.0f);
  }
}

TEST(ObjLoader, TangentsFollowTheUvs) {
  const MeshData m = loadOk(cubeObj());
  // Face 2 (+Z): u runs along +X, v' = 1 - v along -Y.
  for (const Vertex& v : m.vertices)
    if (v.normal[2] == 1.0f) {
      EXPECT_NEAR(v.tangent[0], 1.0f, 1e-6f);
      EXPECT_EQ(v.tangent[3], -1.0f);  // cross(+Z, +X) = +Y, against v'
    }
}

TEST(ObjLoader, MergesShapes) {
  AssetInfo info;
  const MeshData m = loadOk(
      "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
      "o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\nf 4 5 6\n"
      "o empty\n",
      &info);
  EXPECT_EQ(info.shapes, 2u);
  EXPECT_EQ(info.triangles, 3u);
  EXPECT_EQ(m.vertices.size(), 6u);  // the repeated face reuses its vertices
}

TEST(ObjLoader, TriangulatesQuadsAndPentagons) {
  AssetInfo info;
  // A unit square and a regular-ish convex pentagon (area 2.5 + 0.5 = 3) in the z = 0 plane.
  const MeshData m = loadOk(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "v 2 0 0\nv 4 0 0\nv 4 1 0\nv 3 1.5 0\nv 2 1 0\n"
      "f 1 2 3 4\nf 5 6 7 8 9\n",
      &info);
  EXPECT_EQ(info.triangles, 2u + 3u);
  EXPECT_NEAR(totalArea(m), 1.0 + 2.5, 1e-6);  // the pieces cover each polygon exactly once
  for (const Vertex& v : m.vertices) EXPECT_EQ(normal(v), glm::vec3(0, 0, 1));
}

TEST(ObjLoader, NegativeIndicesCountBack) {
  const MeshData m = loadOk("v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n");
  ASSERT_EQ(m.vertices.size(), 3u);
  EXPECT_EQ(position(m.vertices[m.indices[0]]), glm::vec3(0, 0, 0));
  EXPECT_EQ(position(m.vertices[m.indices[2]]), glm::vec3(0, 1, 0));
}

TEST(ObjLoader, AcceptsCrLfCommentsAndAByteOrderMark) {
  AssetInfo info;
  loadOk("\xEF\xBB\xBF# exported\r\nv 0 0 0 # origin\r\nv 1 0 0\r\nv 0 1 0\r\ns off\r\nf 1 2 3\r\n", &info);
  EXPECT_EQ(info.triangles, 1u);
}

// mtllib names a file; parsing from memory must never open it.
TEST(ObjLoader, MtllibNeverReadsAFile) {
  const std::string header = "mtllib ../../etc/passwd\nusemtl root\n";
  AssetInfo info;
  const MeshData m = loadOk(header + "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", &info);
  EXPECT_EQ(info.triangles, 1u);
  EXPECT_EQ(m.name.find("passwd"), std::string::npos);
  auto bad = load(header + "v 0 0 0\nf 1 2 9\n");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().message.find("passwd"), std::string::npos);
  EXPECT_EQ(bad.error().message.find("root:"), std::string::npos);
}

TEST(ObjLoader, RefusesIndexOutOfRange) {
  expectRefused("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", {"line 4", "vertex 9", "only 3"});
  expectRefused("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 -2 -1\n", {"line 4", "counts back 4", "only 3"});
  expectRefused("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n", {"normal 2", "only 1"});
  expectRefused("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", {"line 4", "non-zero"});
}

TEST(ObjLoader, RefusesNonFiniteNumbers) {
  expectRefused("v 1 nan 2\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", {"line 1", "'nan'", "finite"});
  expectRefused("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 inf 1\nf 1 2 3\n", {"line 4", "'inf'", "normal"});
  expectRefused("v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", {"'1e39'", "finite"});  // beyond float
  expectRefused("v 1,5 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", {"'1,5'", "not a number"});
  expectRefused("v 1 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", {"line 1", "has 2 numbers"});
}

TEST(ObjLoader, RefusesACommentAfterAFace) {  // tinyobjloader would fail on it without saying why
  expectRefused("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 # first\n", {"line 4", "comment after a face"});
}

TEST(ObjLoader, ErrorMessagesStayPrintableAscii) {  // they end up in JSON, which must be UTF-8
  auto mesh = load("v 1 \xff\xfe\xc3 2\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.error().message.find("'\\xff\\xfe\\xc3'"), std::string::npos) << mesh.error().message;
  for (char c : mesh.error().message) EXPECT_TRUE(c >= 0x20 && c < 0x7f);
}

TEST(ObjLoader, RefusesAFileWithoutFaces) {
  expectRefused("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\n", {"no faces"});
  expectRefused("", {"no 'v'"});
}

TEST(ObjLoader, RefusesMoreTrianglesThanTheLimit) {
  AssetLimits limits;
  limits.maxTriangles = 11;
  expectRefused(cubeObj(), {"limit of 11 triangles"}, limits);
  limits.maxTriangles = 12;
  EXPECT_TRUE(load(cubeObj(), nullptr, limits).ok());
}

TEST(ObjLoader, RefusesBinaryData) {
  std::mt19937 random(7);
  std::string bytes(4096, '\0');
  for (char& c : bytes) c = static_cast<char>(random() & 0xff);
  expectRefused(bytes, {"not a Wavefront OBJ file"});
  expectRefused(std::string("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\0\0\0", 35), {"line 5", "byte 0x00"});
}

TEST(ObjLoader, RefusesRandomText) {
  expectRefused("Lorem ipsum dolor sit amet,\nconsectetur adipiscing elit.\n", {"not a Wavefront OBJ mesh"});
  expectRefused("{\"mesh\": \"sphere\"}\n", {"not a Wavefront OBJ mesh"});
}

TEST(ObjLoader, RefusesAFileCutInAFaceLine) {
  const std::string obj = cubeObj();
  const std::string cutInCorner = obj.substr(0, obj.size() - 8);  // "... 2/2/6 3/"
  expectRefused(cutInCorner, {"line 24", "face corner '3/3/'"});
  const std::string cutAfterTwoCorners = std::string(kCubePositions) + "f 1 2";
  expectRefused(cutAfterTwoCorners, {"line 9", "at least 3 corners", "has 2"});
}

TEST(ObjLoader, RefusesHugePolygonsAndTagStatements) {
  std::string face = "f";
  for (int i = 1; i <= 300; ++i) face += " " + std::to_string(i);
  std::string obj;
  for (int i = 0; i < 300; ++i) obj += "v " + std::to_string(i) + " " + std::to_string(i * i % 7) + " 0\n";
  expectRefused(obj + face + "\n", {"300 corners", "at most 255"});
  expectRefused("v 0 0 0\nv 1 0 0\nv 0 1 0\nt crease 8192/8192/8192\nf 1 2 3\n", {"line 4", "'t'"});
}

}  // namespace
}  // namespace brdfa
