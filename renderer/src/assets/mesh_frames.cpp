#include "assets/mesh_frames.h"

#include <glm/glm.hpp>

#include <cmath>
#include <cstring>
#include <unordered_map>
#include <vector>

namespace brdfa {

namespace {

glm::dvec3 positionOf(const Vertex& v) { return {v.position[0], v.position[1], v.position[2]}; }
glm::dvec3 normalOf(const Vertex& v) { return {v.normal[0], v.normal[1], v.normal[2]}; }
glm::dvec2 texCoordOf(const Vertex& v) { return {v.texCoord[0], v.texCoord[1]}; }

// A position compared bit for bit, so welding never depends on a tolerance; -0 counts as +0.
struct PositionKey {
  uint32_t bits[3];
  bool operator==(const PositionKey& o) const {
    return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
  }
};

struct PositionKeyHash {
  size_t operator()(const PositionKey& k) const {
    uint64_t h = 1469598103934665603ull;  // FNV-1a over the three words
    for (uint32_t w : k.bits) h = (h ^ w) * 1099511628211ull;
    return static_cast<size_t>(h);
  }
};

PositionKey keyOf(const Vertex& v) {
  PositionKey key;
  for (int i = 0; i < 3; ++i) {
    float x = v.position[i] + 0.0f;  // -0.0f + 0.0f == +0.0f
    std::memcpy(&key.bits[i], &x, sizeof x);
  }
  return key;
}

// For each vertex, the index of the group of vertices sharing its position.
std::vector<uint32_t> positionGroups(const std::vector<Vertex>& vertices, size_t& groupCount) {
  std::unordered_map<PositionKey, uint32_t, PositionKeyHash> groupOf;
  groupOf.reserve(vertices.size());
  std::vector<uint32_t> group(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i)
    group[i] = groupOf.emplace(keyOf(vertices[i]), static_cast<uint32_t>(groupOf.size())).first->second;
  groupCount = groupOf.size();
  return group;
}

// The angle at corner a of the triangle (a, b, c). atan2 of |cross| and dot stays accurate for
// angles near 0 and pi, where acos of a dot product does not; a zero-length edge gives 0.
double cornerAngle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const glm::dvec3 e1 = b - a, e2 = c - a;
  return std::atan2(glm::length(glm::cross(e1, e2)), glm::dot(e1, e2));
}

void setNormal(Vertex& v, const glm::dvec3& n) {
  for (int i = 0; i < 3; ++i) v.normal[i] = static_cast<float>(n[i]);
}

void setTangent(Vertex& v, const glm::dvec3& t, float handedness) {
  for (int i = 0; i < 3; ++i) v.tangent[i] = static_cast<float>(t[i]);
  v.tangent[3] = handedness;
}

// The vertex normal as a unit vector in double precision; +Y where it has none (guards callers
// that skipped generateSmoothNormals: a zero or non-finite normal must not become NaN).
glm::dvec3 unitNormalOf(const Vertex& v) {
  const glm::dvec3 n = normalOf(v);
  const double len = glm::length(n);
  if (!(len > 0.0) || !std::isfinite(len)) return {0.0, 1.0, 0.0};
  return n / len;
}

// One triangle's unit dP/du and dP/dv from its texture coordinates (Lengyel 2001): solve
// [e1 e2] = [dP/du dP/dv] [[s1 s2] [t1 t2]] for the two derivatives. False when the UV triangle
// has (relative to its size) no area, or the triangle itself has none: no direction then.
bool triangleUvDerivatives(const Vertex& v0, const Vertex& v1, const Vertex& v2, glm::dvec3& dpdu, glm::dvec3& dpdv) {
  const glm::dvec3 e1 = positionOf(v1) - positionOf(v0), e2 = positionOf(v2) - positionOf(v0);
  const glm::dvec2 w1 = texCoordOf(v1) - texCoordOf(v0), w2 = texCoordOf(v2) - texCoordOf(v0);
  const double det = w1.x * w2.y - w2.x * w1.y;
  // Zero-area (or sliver, 1e-6 relative) UV triangle: u and v do not vary independently on it.
  if (!(std::abs(det) > 1e-12 * (glm::dot(w1, w1) + glm::dot(w2, w2)))) return false;
  dpdu = (e1 * w2.y - e2 * w1.y) / det;
  dpdv = (e2 * w1.x - e1 * w2.x) / det;
  const double lu = glm::length(dpdu), lv = glm::length(dpdv);
  if (!(lu > 0.0) || !(lv > 0.0) || !std::isfinite(lu) || !std::isfinite(lv)) return false;
  dpdu /= lu;
  dpdv /= lv;
  return true;
}

struct TangentSums {
  glm::dvec3 u{0.0}, v{0.0};
};

// Angle-weighted sums of the unit dP/du and dP/dv of the triangles around each vertex (the same
// weighting as the normals, so a finely split region does not outweigh a coarse one).
std::vector<TangentSums> accumulateUvDerivatives(const MeshData& mesh) {
  std::vector<TangentSums> sums(mesh.vertices.size());
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
    const uint32_t idx[3] = {mesh.indices[i], mesh.indices[i + 1], mesh.indices[i + 2]};
    const Vertex& a = mesh.vertices[idx[0]];
    const Vertex& b = mesh.vertices[idx[1]];
    const Vertex& c = mesh.vertices[idx[2]];
    glm::dvec3 dpdu, dpdv;
    if (!triangleUvDerivatives(a, b, c, dpdu, dpdv)) continue;
    const glm::dvec3 p[3] = {positionOf(a), positionOf(b), positionOf(c)};
    for (int k = 0; k < 3; ++k) {
      const double angle = cornerAngle(p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
      sums[idx[k]].u += angle * dpdu;
      sums[idx[k]].v += angle * dpdv;
    }
  }
  return sums;
}

// The fallback frame's tangent for normal n: orthonormalBasis's first vector, with w = +1
// because that basis is right-handed (cross(n, t) = b).
void setFallbackTangent(Vertex& v, const glm::dvec3& n) {
  glm::vec3 t, b;
  orthonormalBasis(glm::vec3(n), t, b);
  setTangent(v, glm::dvec3(t), 1.0f);
}

// Gram-Schmidt of the summed dP/du against n; false when nothing usable is left.
bool tangentFromSums(const TangentSums& sums, const glm::dvec3& n, glm::dvec3& t, float& handedness) {
  const double lu = glm::length(sums.u);
  if (!(lu > 1e-12) || !std::isfinite(lu)) return false;  // no UV triangle, or opposite ones cancel
  t = sums.u / lu - n * glm::dot(n, sums.u / lu);
  const double lt = glm::length(t);
  if (!(lt > 1e-3)) return false;  // dP/du within ~0.06 degrees of the normal: direction is noise
  t /= lt;
  handedness = glm::dot(glm::cross(n, t), sums.v) < 0.0 ? -1.0f : 1.0f;
  return true;
}

}  // namespace

void generateSmoothNormals(MeshData& mesh) {
  size_t groupCount = 0;
  const std::vector<uint32_t> group = positionGroups(mesh.vertices, groupCount);
  std::vector<glm::dvec3> sum(groupCount, glm::dvec3(0.0));
  for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
    const uint32_t idx[3] = {mesh.indices[i], mesh.indices[i + 1], mesh.indices[i + 2]};
    const glm::dvec3 p[3] = {positionOf(mesh.vertices[idx[0]]), positionOf(mesh.vertices[idx[1]]),
                             positionOf(mesh.vertices[idx[2]])};
    glm::dvec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
    const double len = glm::length(n);
    if (!(len > 0.0) || !std::isfinite(len)) continue;  // zero-area triangle: no direction to add
    n /= len;
    for (int k = 0; k < 3; ++k) sum[group[idx[k]]] += cornerAngle(p[k], p[(k + 1) % 3], p[(k + 2) % 3]) * n;
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const glm::dvec3 s = sum[group[i]];
    const double len = glm::length(s);
    // Guard: an unused vertex, or neighbours facing exactly opposite ways, sum to ~0.
    setNormal(mesh.vertices[i], len > 1e-12 && std::isfinite(len) ? s / len : glm::dvec3(0.0, 1.0, 0.0));
  }
}

void generateTangents(MeshData& mesh, bool hasTexCoords) {
  const std::vector<TangentSums> sums =
      hasTexCoords ? accumulateUvDerivatives(mesh) : std::vector<TangentSums>(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    Vertex& v = mesh.vertices[i];
    const glm::dvec3 n = unitNormalOf(v);
    glm::dvec3 t;
    float handedness = 1.0f;
    if (tangentFromSums(sums[i], n, t, handedness))
      setTangent(v, t, handedness);
    else
      setFallbackTangent(v, n);
  }
}

void orthonormalBasis(const glm::vec3& n, glm::vec3& t, glm::vec3& b) {
  // Duff et al. 2017, listing 3, with the sign test of shaders/lib/frame.glsl (n.z = -0 counts
  // as positive there; copysign would not) so both give the same frame.
  const float s = n.z >= 0.0f ? 1.0f : -1.0f;
  const float a = -1.0f / (s + n.z);
  const float c = n.x * n.y * a;
  t = glm::vec3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
  b = glm::vec3(c, s + n.y * n.y * a, -n.y);
}

}  // namespace brdfa
