// The built-in meshes (renderer/src/assets/meshes.h) and the frame generators (mesh_frames.h): finite,
// unit, orthogonal frames, outward winding, tangents along increasing u, and Newell's teapot
// checked against the well-known facts of its original data.
#include <gtest/gtest.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "assets/mesh_frames.h"
#include "assets/meshes.h"
#include "assets/teapot_patches.h"

namespace brdfa {
namespace {

glm::vec3 position(const Vertex& v) { return {v.position[0], v.position[1], v.position[2]}; }
glm::vec3 normal(const Vertex& v) { return {v.normal[0], v.normal[1], v.normal[2]}; }
glm::vec3 tangent(const Vertex& v) { return {v.tangent[0], v.tangent[1], v.tangent[2]}; }
glm::vec2 texCoord(const Vertex& v) { return {v.texCoord[0], v.texCoord[1]}; }

bool finite(const Vertex& v) {
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(v.position[k]) || !std::isfinite(v.normal[k])) return false;
  for (int k = 0; k < 4; ++k)
    if (!std::isfinite(v.tangent[k])) return false;
  return std::isfinite(v.texCoord[0]) && std::isfinite(v.texCoord[1]);
}

MeshData builtin(const std::string& name) {
  auto mesh = makeBuiltinMesh(name);
  EXPECT_TRUE(mesh.ok()) << name;
  return mesh.ok() ? std::move(mesh).value() : MeshData{};
}

glm::vec3 triangleNormal(const MeshData& m, size_t t) {
  const glm::vec3 p0 = position(m.vertices[m.indices[3 * t]]);
  return glm::cross(position(m.vertices[m.indices[3 * t + 1]]) - p0, position(m.vertices[m.indices[3 * t + 2]]) - p0);
}

// Every vertex: finite, unit normal, unit tangent orthogonal to it, handedness +-1.
void expectValidFrames(const MeshData& m) {
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    const Vertex& v = m.vertices[i];
    ASSERT_TRUE(finite(v)) << m.name << " vertex " << i;
    ASSERT_NEAR(glm::length(normal(v)), 1.0f, 1e-4f) << m.name << " vertex " << i;
    ASSERT_NEAR(glm::length(tangent(v)), 1.0f, 1e-4f) << m.name << " vertex " << i;
    ASSERT_NEAR(glm::dot(normal(v), tangent(v)), 0.0f, 1e-4f) << m.name << " vertex " << i;
    ASSERT_TRUE(v.tangent[3] == 1.0f || v.tangent[3] == -1.0f) << m.name << " vertex " << i;
  }
}

// Indices in range, whole triangles, none without area.
void expectValidTriangles(const MeshData& m) {
  ASSERT_FALSE(m.indices.empty()) << m.name;
  ASSERT_EQ(m.indices.size() % 3, 0u) << m.name;
  for (uint32_t index : m.indices) ASSERT_LT(index, m.vertices.size()) << m.name;
  for (size_t t = 0; t < m.indices.size() / 3; ++t) {
    const float area2 = glm::length(triangleNormal(m, t));
    ASSERT_TRUE(std::isfinite(area2) && area2 > 0.0f) << m.name << " triangle " << t;
  }
}

// Counter-clockwise from outside: each triangle's geometric normal agrees with its vertex normals.
void expectWindingMatchesNormals(const MeshData& m) {
  for (size_t t = 0; t < m.indices.size() / 3; ++t) {
    const glm::vec3 g = triangleNormal(m, t);
    for (int k = 0; k < 3; ++k)
      ASSERT_GT(glm::dot(g, normal(m.vertices[m.indices[3 * t + k]])), 0.0f) << m.name << " triangle " << t;
  }
}

// Tangents point along increasing u, and B = w cross(N, T) along increasing v, as each
// triangle's own dP/du, dP/dv (from its UVs) say.
void expectTangentsFollowUv(const MeshData& m) {
  size_t checked = 0;
  for (size_t t = 0; t < m.indices.size() / 3; ++t) {
    const Vertex* v[3] = {&m.vertices[m.indices[3 * t]], &m.vertices[m.indices[3 * t + 1]],
                          &m.vertices[m.indices[3 * t + 2]]};
    const glm::vec3 e1 = position(*v[1]) - position(*v[0]), e2 = position(*v[2]) - position(*v[0]);
    const glm::vec2 w1 = texCoord(*v[1]) - texCoord(*v[0]), w2 = texCoord(*v[2]) - texCoord(*v[0]);
    const float det = w1.x * w2.y - w2.x * w1.y;
    if (std::abs(det) < 1e-12f) continue;
    const glm::vec3 dpdu = (e1 * w2.y - e2 * w1.y) / det, dpdv = (e2 * w1.x - e1 * w2.x) / det;
    for (const Vertex* c : v) {
      const glm::vec3 b = c->tangent[3] * glm::cross(normal(*c), tangent(*c));
      ASSERT_GT(glm::dot(tangent(*c), dpdu), 0.0f) << m.name << " triangle " << t;
      ASSERT_GT(glm::dot(b, dpdv), 0.0f) << m.name << " triangle " << t;
    }
    ++checked;
  }
  EXPECT_GT(checked, 0u) << m.name;
}

// Divergence theorem: the signed volume is positive for a closed, outward-wound mesh.
double signedVolume(const MeshData& m) {
  double volume = 0;
  for (size_t t = 0; t < m.indices.size() / 3; ++t) {
    const glm::dvec3 p0 = position(m.vertices[m.indices[3 * t]]), p1 = position(m.vertices[m.indices[3 * t + 1]]),
                     p2 = position(m.vertices[m.indices[3 * t + 2]]);
    volume += glm::dot(p0, glm::cross(p1, p2)) / 6.0;
  }
  return volume;
}

struct Bounds {
  glm::vec3 lo{INFINITY}, hi{-INFINITY};
  float maxRadius = 0;
};

Bounds boundsOf(const MeshData& m) {
  Bounds b;
  for (const Vertex& v : m.vertices) {
    b.lo = glm::min(b.lo, position(v));
    b.hi = glm::max(b.hi, position(v));
    b.maxRadius = std::max(b.maxRadius, glm::length(position(v)));
  }
  return b;
}

TEST(Meshes, NamesAreTheSixBuiltins) {
  const std::vector<std::string> expected{"sphere", "plane", "cube", "torus", "teapot", "dense_sphere"};
  EXPECT_EQ(builtinMeshNames(), expected);
  auto unknown = makeBuiltinMesh("sphere2");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::NotFound);
  EXPECT_NE(unknown.error().message.find("sphere2"), std::string::npos);
}

TEST(Meshes, EveryBuiltinHasValidFramesAndTriangles) {
  for (const std::string& name : builtinMeshNames()) {
    SCOPED_TRACE(name);
    const MeshData m = builtin(name);
    EXPECT_EQ(m.name, name);
    expectValidFrames(m);
    expectValidTriangles(m);
    expectWindingMatchesNormals(m);
    expectTangentsFollowUv(m);
    const Bounds b = boundsOf(m);
    EXPECT_TRUE(glm::all(glm::greaterThanEqual(b.lo, glm::vec3(-1.0f - 1e-5f)))) << name;
    EXPECT_TRUE(glm::all(glm::lessThanEqual(b.hi, glm::vec3(1.0f + 1e-5f)))) << name;
    if (name != "cube" && name != "plane") {
      EXPECT_LE(b.maxRadius, 1.0f + 1e-5f) << name;
    }
  }
}

TEST(Meshes, ClosedBuiltinsEncloseTheirVolumeOutward) {
  const double pi = 3.14159265358979323846;
  EXPECT_NEAR(signedVolume(builtin("sphere")), 4.0 / 3.0 * pi, 0.01);
  EXPECT_NEAR(signedVolume(builtin("dense_sphere")), 4.0 / 3.0 * pi, 0.001);
  EXPECT_NEAR(signedVolume(builtin("cube")), 8.0, 1e-5);
  EXPECT_NEAR(signedVolume(builtin("torus")), 2 * pi * pi * 0.7 * 0.3 * 0.3, 0.005);  // 2 pi^2 R r^2
  EXPECT_GT(signedVolume(builtin("teapot")), 0.1);  // open where spout and handle meet the body
}

TEST(Meshes, SphereIsUnchangedUnitUvSphere) {
  const MeshData m = builtin("sphere");
  EXPECT_EQ(m.vertices.size(), 129u * 65u);
  for (const Vertex& v : m.vertices) {
    ASSERT_NEAR(glm::length(position(v)), 1.0f, 1e-5f);
    ASSERT_NEAR(glm::dot(normal(v), position(v)), 1.0f, 1e-5f);
  }
  // At (0, 0, 1): T = +X, v runs down so B = -Y and w = -1 (the convention in meshes.h).
  const Vertex& front = m.vertices[32 * 129 + 0];
  EXPECT_NEAR(front.position[2], 1.0f, 1e-6f);
  EXPECT_NEAR(front.tangent[0], 1.0f, 1e-6f);
  EXPECT_EQ(front.tangent[3], -1.0f);
}

TEST(Meshes, PlaneIsTwoByTwoFacingUp) {
  const MeshData m = builtin("plane");
  EXPECT_EQ(m.indices.size(), 6u);
  for (const Vertex& v : m.vertices) {
    EXPECT_EQ(v.position[1], 0.0f);
    EXPECT_EQ(std::abs(v.position[0]), 1.0f);
    EXPECT_EQ(std::abs(v.position[2]), 1.0f);
    EXPECT_EQ(normal(v), glm::vec3(0, 1, 0));
    EXPECT_EQ(tangent(v), glm::vec3(1, 0, 0));
    // u = (x + 1) / 2 and v = (z + 1) / 2: the image's top row at the far edge z = -1.
    EXPECT_FLOAT_EQ(v.texCoord[0], (v.position[0] + 1) / 2);
    EXPECT_FLOAT_EQ(v.texCoord[1], (v.position[2] + 1) / 2);
  }
}

TEST(Meshes, CubeHasFlatFacesWithOwnUvs) {
  const MeshData m = builtin("cube");
  EXPECT_EQ(m.vertices.size(), 24u);
  EXPECT_EQ(m.indices.size(), 36u);
  for (const Vertex& v : m.vertices) {
    const glm::vec3 n = normal(v);
    EXPECT_FLOAT_EQ(glm::dot(glm::abs(n), glm::vec3(1)), 1.0f);  // axis-aligned
    EXPECT_FLOAT_EQ(glm::dot(position(v), n), 1.0f);             // on the face the normal names
    EXPECT_TRUE(v.texCoord[0] == 0.0f || v.texCoord[0] == 1.0f);
    EXPECT_TRUE(v.texCoord[1] == 0.0f || v.texCoord[1] == 1.0f);
  }
}

TEST(Meshes, TorusHasItsRadii) {
  const MeshData m = builtin("torus");
  EXPECT_EQ(m.vertices.size(), 129u * 65u);
  for (const Vertex& v : m.vertices) {
    const glm::vec3 p = position(v);
    const glm::vec3 centre = 0.7f * glm::normalize(glm::vec3(p.x, 0, p.z));  // nearest point of the core circle
    ASSERT_NEAR(glm::length(p - centre), 0.3f, 1e-5f);
    ASSERT_NEAR(glm::dot(normal(v), glm::normalize(p - centre)), 1.0f, 1e-5f);  // analytic normal
  }
}

TEST(Meshes, DenseSphereHasAboutHalfAMillionTriangles) {
  const MeshData m = builtin("dense_sphere");
  const size_t triangles = m.indices.size() / 3;
  EXPECT_GE(triangles, 450'000u);
  EXPECT_LE(triangles, 550'000u);
  for (const Vertex& v : m.vertices) ASSERT_NEAR(glm::length(position(v)), 1.0f, 1e-5f);
}

// The facts of the original data (z up): the body's rim has radius 1.5 at z = 2.4 and its widest
// ring radius 2 at z = 0.9 (both rows of control points lie on the surface), the bottom is at
// z = 0 and the knob's top at 3.15, the spout tip near x = 3.43 and the handle at x = -3.
// Any typo in the table moves one of these.
TEST(Meshes, TeapotDataMatchesTheKnownDimensions) {
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (int p = 0; p < teapot::kPatchCount; ++p)
    for (int i = 0; i <= 32; ++i)
      for (int j = 0; j <= 32; ++j) {
        const glm::dvec3 q = evaluateTeapotPatch(p, j / 32.0, i / 32.0).position;
        lo = glm::min(lo, q);
        hi = glm::max(hi, q);
      }
  EXPECT_NEAR(lo.z, 0.0, 1e-9);
  EXPECT_NEAR(hi.z, 3.15, 1e-6);
  EXPECT_NEAR(lo.x, -3.0, 1e-6);   // handle
  EXPECT_NEAR(hi.x, 3.434, 0.01);  // spout tip
  EXPECT_NEAR(lo.y, -2.0, 1e-6);   // body, widest
  EXPECT_NEAR(hi.y, 2.0, 1e-6);
  for (int p = 4; p < 8; ++p)  // upper body patches: top edge is the rim circle
    for (int j = 0; j <= 8; ++j) {
      const glm::dvec3 q = evaluateTeapotPatch(p, j / 8.0, 0.0).position;
      EXPECT_NEAR(q.z, 2.4, 1e-6);
      EXPECT_NEAR(std::hypot(q.x, q.y), 1.5, 0.01);  // Newell's quarter circles bulge by < 0.5 %
    }
  for (int p = 0; p < teapot::kPatchCount; ++p)
    for (int k = 0; k < 16; ++k) {
      ASSERT_GE(teapot::kPatches[p][k], 1);
      ASSERT_LE(teapot::kPatches[p][k], teapot::kControlPointCount);
    }
}

// cross(dP/du, dP/dv) points away from the inside at each patch's centre: from a point on the z
// axis half-way up for rim, body and lid, from the z axis for the knob (its side faces partly
// down), from the midplane y = 0 for handle and spout, downward for the bottom.
TEST(Meshes, TeapotPatchesFaceOutward) {
  for (int p = 0; p < teapot::kPatchCount; ++p) {
    const SurfacePoint s = evaluateTeapotPatch(p, 0.5, 0.5);
    const glm::dvec3 n = glm::cross(s.dPdu, s.dPdv);
    const bool tube = p >= teapot::kFirstTubePatch && p < teapot::kEndTubePatch;
    const bool knob = p >= 20 && p < 24, bottom = p >= 28;
    const glm::dvec3 away = tube     ? glm::dvec3(0, s.position.y, 0)
                            : knob   ? glm::dvec3(s.position.x, s.position.y, 0)
                            : bottom ? glm::dvec3(0, 0, -1)
                                     : s.position - glm::dvec3(0, 0, 1.5);
    EXPECT_GT(glm::dot(n, away), 0.0) << "patch " << p;
  }
}

TEST(Meshes, TeapotIsUprightWithTheSpoutTowardPlusX) {
  const MeshData m = builtin("teapot");
  const Bounds b = boundsOf(m);
  const glm::vec3 size = b.hi - b.lo;
  const float width = 3.0f + 3.434f;
  EXPECT_NEAR(size.y / size.x, 3.15f / width, 0.01f);
  EXPECT_NEAR(size.z / size.x, 4.0f / width, 0.01f);
  EXPECT_NEAR(b.maxRadius, 1.0f, 0.01f);
  EXPECT_NEAR(glm::length(0.5f * (b.lo + b.hi)), 0.0f, 1e-5f);
  // The spout tip is the rightmost point and sits high (z ~ 2.47 of 3.15); the handle's outer
  // edge is the leftmost (z 1.8 .. 2.25).
  const Vertex* right = &m.vertices[0];
  const Vertex* left = &m.vertices[0];
  for (const Vertex& v : m.vertices) {
    if (v.position[0] > right->position[0]) right = &v;
    if (v.position[0] < left->position[0]) left = &v;
  }
  EXPECT_NEAR((right->position[1] - b.lo.y) / size.y, 2.47f / 3.15f, 0.03f);
  const float handleHeight = (left->position[1] - b.lo.y) / size.y;
  EXPECT_GE(handleHeight, 1.8f / 3.15f - 0.01f);
  EXPECT_LE(handleHeight, 2.25f / 3.15f + 0.01f);
  // The knob's top is the highest point, with a normal straight up despite the pole there.
  const Vertex* top = &m.vertices[0];
  for (const Vertex& v : m.vertices)
    if (v.position[1] > top->position[1]) top = &v;
  EXPECT_GT(top->normal[1], 0.999f);
}

TEST(MeshFrames, SmoothNormalsOfASphereArePositions) {
  MeshData m = makeUvSphere(64, 32);
  for (uint32_t i = 0; i <= 32; ++i)  // weld the seam: the u = 1 copy at the u = 0 position
    std::copy(m.vertices[i * 65].position, m.vertices[i * 65].position + 3, m.vertices[i * 65 + 64].position);
  for (Vertex& v : m.vertices) v.normal[0] = v.normal[1] = v.normal[2] = 0.0f;
  generateSmoothNormals(m);
  std::vector<bool> used(m.vertices.size(), false);
  for (uint32_t i : m.indices) used[i] = true;
  // Angle weighting is exact on the sphere but for the thin triangles next to the poles. (A pole
  // copy no triangle uses gets the +Y fallback.)
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    if (!used[i]) continue;
    ASSERT_GT(glm::dot(normal(m.vertices[i]), position(m.vertices[i])), 0.998f) << i;
  }
  // Copies of a position (the seam's u = 0 and u = 1) share one normal: no crease at the seam.
  for (uint32_t i = 0; i <= 32; ++i) EXPECT_EQ(normal(m.vertices[i * 65]), normal(m.vertices[i * 65 + 64]));
}

TEST(MeshFrames, SmoothNormalsIgnoreZeroAreaTriangles) {
  MeshData m;
  m.vertices.resize(4);
  const float p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}};
  for (int i = 0; i < 4; ++i) std::copy(p[i], p[i] + 3, m.vertices[i].position);
  m.indices = {0, 1, 2, 0, 1, 3};  // the second is a line
  generateSmoothNormals(m);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(normal(m.vertices[i]), glm::vec3(0, 0, 1));
  EXPECT_EQ(normal(m.vertices[3]), glm::vec3(0, 1, 0));  // only in the line: the +Y fallback
}

TEST(MeshFrames, TangentsFromUvsMatchTheSphereAnalytically) {
  const MeshData analytic = makeUvSphere(64, 32);
  MeshData m = analytic;
  generateTangents(m, true);
  std::vector<bool> used(m.vertices.size(), false);
  for (uint32_t i : m.indices) used[i] = true;
  expectValidFrames(m);
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    if (!used[i]) continue;  // a pole copy no triangle touches
    ASSERT_GT(glm::dot(tangent(m.vertices[i]), tangent(analytic.vertices[i])), 0.99f) << i;
    ASSERT_EQ(m.vertices[i].tangent[3], analytic.vertices[i].tangent[3]) << i;
  }
}

TEST(MeshFrames, WithoutUvsTangentsAreTheStableFallback) {
  MeshData m = makeUvSphere(16, 8);
  generateTangents(m, false);
  expectValidFrames(m);
  for (const Vertex& v : m.vertices) {
    glm::vec3 t, b;
    orthonormalBasis(normal(v), t, b);
    ASSERT_LT(glm::length(tangent(v) - t), 1e-6f);  // the same up to the normal's rounding
    ASSERT_EQ(v.tangent[3], 1.0f);
  }
}

TEST(MeshFrames, DegenerateUvTrianglesFallBack) {
  MeshData m = makeUvSphere(16, 8);
  for (Vertex& v : m.vertices) v.texCoord[0] = v.texCoord[1] = 0.25f;  // every UV triangle has no area
  generateTangents(m, true);
  expectValidFrames(m);
  glm::vec3 t, b;
  orthonormalBasis(normal(m.vertices[40]), t, b);
  EXPECT_LT(glm::length(tangent(m.vertices[40]) - t), 1e-6f);
}

TEST(MeshFrames, OrthonormalBasisIsRightHandedEverywhere) {
  const glm::vec3 normals[] = {{0, 0, 1},
                               {0, 0, -1},
                               {1, 0, 0},
                               {0, -1, 0},
                               {0.6f, 0, -0.8f},
                               glm::normalize(glm::vec3(1, 2, 3)),
                               glm::normalize(glm::vec3(1e-4f, -1e-4f, -1))};
  for (glm::vec3 n : normals) {
    glm::vec3 t, b;
    orthonormalBasis(n, t, b);
    EXPECT_NEAR(glm::length(t), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::length(b), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(t, n), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(b, n), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::length(glm::cross(n, t) - b), 0.0f, 1e-5f);
  }
}

}  // namespace
}  // namespace brdfa
