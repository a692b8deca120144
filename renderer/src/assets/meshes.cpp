#include "assets/meshes.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <functional>

#include "assets/mesh_frames.h"
#include "assets/teapot_patches.h"

namespace brdfa {

MeshData makeUvSphere(uint32_t segments, uint32_t rings) {
  MeshData mesh;
  mesh.name = "sphere";
  const float pi = 3.14159265358979323846f;
  for (uint32_t i = 0; i <= rings; ++i) {
    float v = static_cast<float>(i) / static_cast<float>(rings);
    float theta = v * pi;
    for (uint32_t j = 0; j <= segments; ++j) {
      float u = static_cast<float>(j) / static_cast<float>(segments);
      float phi = u * 2.0f * pi;
      glm::vec3 p(std::sin(theta) * std::sin(phi), std::cos(theta), std::sin(theta) * std::cos(phi));
      glm::vec3 t(std::cos(phi), 0.0f, -std::sin(phi));  // d p / d phi, normalized; defined at the poles too
      glm::vec3 b(std::cos(theta) * std::sin(phi), -std::sin(theta), std::cos(theta) * std::cos(phi));  // d p / d theta
      float handedness = glm::dot(glm::cross(p, t), b) < 0.0f ? -1.0f : 1.0f;
      mesh.vertices.push_back(Vertex{{p.x, p.y, p.z}, {p.x, p.y, p.z}, {u, v}, {t.x, t.y, t.z, handedness}});
    }
  }
  const uint32_t stride = segments + 1;
  for (uint32_t i = 0; i < rings; ++i)
    for (uint32_t j = 0; j < segments; ++j) {
      uint32_t a = i * stride + j, b = (i + 1) * stride + j, c = b + 1, d = a + 1;
      // Skip the degenerate triangle of each pole quad.
      if (i != 0) mesh.indices.insert(mesh.indices.end(), {a, b, d});
      if (i + 1 != rings) mesh.indices.insert(mesh.indices.end(), {d, b, c});
    }
  return mesh;
}

namespace {

constexpr double kPi = 3.14159265358979323846;

using Surface = std::function<SurfacePoint(double u, double v)>;

// How a parametric surface becomes a grid of vertices: segments along u and v, the texture
// coordinates of the parameter square's corner (0, 0) and their growth per unit of (u, v), and
// which side of cross(dP/du, dP/dv) is outside (+1 or -1).
struct GridSpec {
  uint32_t segmentsU = 1, segmentsV = 1;
  glm::dvec2 uvOrigin{0.0}, uvScale{1.0};
  double outside = 1.0;
};

// True where the derivatives give no normal: one vanishes (a pole, where a whole row of control
// points is one point) or they are parallel. Scale-free: at a pole the vanishing derivative is
// rounding noise (~1e-16) next to the other.
bool degenerateDerivatives(const SurfacePoint& s) {
  const double lu = glm::length(s.dPdu), lv = glm::length(s.dPdv);
  if (!(std::min(lu, lv) > 1e-9 * std::max(lu, lv))) return true;
  const double sine = glm::length(glm::cross(s.dPdu, s.dPdv)) / (lu * lv);
  return !(sine > 1e-6);
}

// The frame at (u, v). At a degenerate point the surface is evaluated a little inside the
// parameter square instead (1e-4 of it, toward its centre): at the poles of surfaces of
// revolution this gives the limit normal within ~1e-4 rad and a tangent along the ring.
SurfacePoint frameSample(const Surface& surface, double u, double v) {
  SurfacePoint s = surface(u, v);
  if (!degenerateDerivatives(s)) return s;
  constexpr double kInset = 1e-4;
  const SurfacePoint inside = surface(u < 0.5 ? u + kInset : u - kInset, v < 0.5 ? v + kInset : v - kInset);
  s.dPdu = inside.dPdu;
  s.dPdv = inside.dPdv;
  return s;
}

Vertex surfaceVertex(const Surface& surface, double u, double v, const GridSpec& spec) {
  const SurfacePoint s = frameSample(surface, u, v);
  const glm::dvec3 n = spec.outside * glm::normalize(glm::cross(s.dPdu, s.dPdv));
  glm::dvec3 t = s.dPdu - n * glm::dot(n, s.dPdu);
  float handedness = 1.0f;
  const double lt = glm::length(t);
  if (lt > 0.0) {
    t /= lt;
    handedness = glm::dot(glm::cross(n, t), s.dPdv) < 0.0 ? -1.0f : 1.0f;
  } else {  // guard: unreachable after frameSample (dP/du would lie along n), kept unit anyway
    glm::vec3 ft, fb;
    orthonormalBasis(glm::vec3(n), ft, fb);
    t = glm::dvec3(ft);
  }
  const glm::dvec2 uv = spec.uvOrigin + spec.uvScale * glm::dvec2(u, v);
  Vertex out{};
  for (int k = 0; k < 3; ++k) {
    out.position[k] = static_cast<float>(s.position[k]);
    out.normal[k] = static_cast<float>(n[k]);
    out.tangent[k] = static_cast<float>(t[k]);
  }
  out.tangent[3] = handedness;
  out.texCoord[0] = static_cast<float>(uv.x);
  out.texCoord[1] = static_cast<float>(uv.y);
  return out;
}

// True for a triangle with (relative to its edges) no area, like the one of each quad that
// touches a pole: its geometric normal would be noise.
bool slivered(const Vertex& a, const Vertex& b, const Vertex& c) {
  const glm::vec3 pa(a.position[0], a.position[1], a.position[2]);
  const glm::vec3 e1 = glm::vec3(b.position[0], b.position[1], b.position[2]) - pa;
  const glm::vec3 e2 = glm::vec3(c.position[0], c.position[1], c.position[2]) - pa;
  const float area2 = glm::length(glm::cross(e1, e2));
  return !(area2 > 1e-6f * (glm::dot(e1, e1) + glm::dot(e2, e2)));
}

void appendTriangle(MeshData& mesh, uint32_t a, uint32_t b, uint32_t c) {
  if (slivered(mesh.vertices[a], mesh.vertices[b], mesh.vertices[c])) return;
  mesh.indices.insert(mesh.indices.end(), {a, b, c});
}

// Appends the (segmentsU + 1) x (segmentsV + 1) grid of surface vertices over [0, 1]^2 and its
// triangles, wound counter-clockwise seen from spec.outside.
void appendSurfaceGrid(MeshData& mesh, const Surface& surface, const GridSpec& spec) {
  const uint32_t base = static_cast<uint32_t>(mesh.vertices.size());
  const uint32_t stride = spec.segmentsU + 1;
  for (uint32_t i = 0; i <= spec.segmentsV; ++i)
    for (uint32_t j = 0; j <= spec.segmentsU; ++j)
      mesh.vertices.push_back(surfaceVertex(surface, double(j) / spec.segmentsU, double(i) / spec.segmentsV, spec));
  for (uint32_t i = 0; i < spec.segmentsV; ++i)
    for (uint32_t j = 0; j < spec.segmentsU; ++j) {
      // a -> b runs along u, a -> d along v: (a, b, c) turns counter-clockwise about dP/du x dP/dv.
      const uint32_t a = base + i * stride + j, b = a + 1, c = b + stride, d = a + stride;
      if (spec.outside > 0.0) {
        appendTriangle(mesh, a, b, c);
        appendTriangle(mesh, a, c, d);
      } else {
        appendTriangle(mesh, a, c, b);
        appendTriangle(mesh, a, d, c);
      }
    }
}

// A flat square face: centre + (2u - 1) right + (2v - 1) down, so its texture appears upright
// seen from `normal`'s side with `right` to the right and `down` toward the image bottom.
void appendSquare(MeshData& mesh, glm::dvec3 centre, glm::dvec3 right, glm::dvec3 down, glm::dvec3 normal) {
  GridSpec spec;
  spec.outside = glm::dot(glm::cross(right, down), normal) > 0.0 ? 1.0 : -1.0;
  auto square = [=](double u, double v) {
    return SurfacePoint{centre + (2 * u - 1) * right + (2 * v - 1) * down, 2.0 * right, 2.0 * down};
  };
  appendSurfaceGrid(mesh, square, spec);
}

MeshData makePlane() {
  MeshData mesh;
  mesh.name = "plane";
  // Seen from above with -Z away from the viewer, the image's top row lies at z = -1.
  appendSquare(mesh, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0});
  return mesh;
}

MeshData makeCube() {
  MeshData mesh;
  mesh.name = "cube";
  const glm::dvec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  // Side faces upright with +Y up; top and bottom as the plane (top row toward -Z, resp. +Z).
  appendSquare(mesh, z, x, -y, z);
  appendSquare(mesh, x, -z, -y, x);
  appendSquare(mesh, -z, -x, -y, -z);
  appendSquare(mesh, -x, z, -y, -x);
  appendSquare(mesh, y, x, z, y);
  appendSquare(mesh, -y, x, -z, -y);
  return mesh;
}

// Torus around +Y: u runs around the Y axis (angle theta, like the sphere's longitude), v
// around the tube (angle phi, from the outer equator up over the top). cross(dP/du, dP/dv) is
// the outward normal cos(phi) e + sin(phi) Y, e = (sin theta, 0, cos theta).
MeshData makeTorus(double major, double minor, uint32_t segments, uint32_t rings) {
  MeshData mesh;
  mesh.name = "torus";
  auto torus = [=](double u, double v) {
    const double theta = 2 * kPi * u, phi = 2 * kPi * v;
    const glm::dvec3 e(std::sin(theta), 0, std::cos(theta)), de(std::cos(theta), 0, -std::sin(theta));
    const glm::dvec3 up(0, 1, 0);
    const double ring = major + minor * std::cos(phi);
    return SurfacePoint{ring * e + minor * std::sin(phi) * up, 2 * kPi * ring * de,
                        2 * kPi * minor * (-std::sin(phi) * e + std::cos(phi) * up)};
  };
  GridSpec spec;
  spec.segmentsU = segments;
  spec.segmentsV = rings;
  appendSurfaceGrid(mesh, torus, spec);
  return mesh;
}

// Cubic Bernstein polynomials and their derivatives at t.
void bernstein(double t, double b[4], double db[4]) {
  const double s = 1.0 - t;
  b[0] = s * s * s;
  b[1] = 3 * t * s * s;
  b[2] = 3 * t * t * s;
  b[3] = t * t * t;
  db[0] = -3 * s * s;
  db[1] = 3 * s * s - 6 * t * s;
  db[2] = 6 * t * s - 3 * t * t;
  db[3] = 3 * t * t;
}

// Rotates the teapot's z-up frame to +Y up: (x, y, z) -> (x, z, -y), a proper rotation, so the
// winding and every cross product keep their sense (the spout stays at +X).
glm::dvec3 zUpToYUp(const glm::dvec3& p) { return {p.x, p.z, -p.y}; }

void rotateZUpToYUp(Vertex& v) {
  const glm::dvec3 p = zUpToYUp({v.position[0], v.position[1], v.position[2]});
  const glm::dvec3 n = zUpToYUp({v.normal[0], v.normal[1], v.normal[2]});
  const glm::dvec3 t = zUpToYUp({v.tangent[0], v.tangent[1], v.tangent[2]});
  for (int k = 0; k < 3; ++k) {
    v.position[k] = static_cast<float>(p[k]);
    v.normal[k] = static_cast<float>(n[k]);
    v.tangent[k] = static_cast<float>(t[k]);
  }
}

// Moves the centre of the bounding box to the origin and scales the farthest vertex to radius 1.
void centreInUnitSphere(MeshData& mesh) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const Vertex& v : mesh.vertices) {
    const glm::vec3 p(v.position[0], v.position[1], v.position[2]);
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::vec3 centre = 0.5f * (lo + hi);
  float radius = 0.0f;
  for (const Vertex& v : mesh.vertices)
    radius = std::max(radius, glm::length(glm::vec3(v.position[0], v.position[1], v.position[2]) - centre));
  for (Vertex& v : mesh.vertices)
    for (int k = 0; k < 3; ++k) v.position[k] = (v.position[k] - centre[k]) / radius;
}

MeshData makeTeapot(uint32_t segmentsPerPatch) {
  MeshData mesh;
  mesh.name = "teapot";
  for (int p = 0; p < teapot::kPatchCount; ++p) {
    // u wraps once around each ring of patches (two around the handle and spout, four around
    // the z axis elsewhere); v runs 0..1 down each patch.
    const int ring = p >= teapot::kFirstTubePatch && p < teapot::kEndTubePatch ? 2 : 4;
    GridSpec spec;
    spec.segmentsU = spec.segmentsV = segmentsPerPatch;
    spec.uvOrigin = {double(p % ring) / ring, 0.0};
    spec.uvScale = {1.0 / ring, 1.0};
    appendSurfaceGrid(
        mesh, [p](double u, double v) { return evaluateTeapotPatch(p, u, v); }, spec);
  }
  for (Vertex& v : mesh.vertices) rotateZUpToYUp(v);
  centreInUnitSphere(mesh);
  return mesh;
}

MeshData renamed(MeshData mesh, const char* name) {
  mesh.name = name;
  return mesh;
}

}  // namespace

SurfacePoint evaluateTeapotPatch(int patch, double u, double v) {
  double bu[4], dbu[4], bv[4], dbv[4];
  bernstein(u, bu, dbu);
  bernstein(v, bv, dbv);
  SurfacePoint s{glm::dvec3(0.0), glm::dvec3(0.0), glm::dvec3(0.0)};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      const float* q = teapot::kControlPoints[teapot::kPatches[patch][4 * r + c] - 1];
      const glm::dvec3 point(q[0], q[1], q[2]);
      s.position += bv[r] * bu[c] * point;
      s.dPdu += bv[r] * dbu[c] * point;
      s.dPdv += dbv[r] * bu[c] * point;
    }
  return s;
}

std::vector<std::string> builtinMeshNames() { return {"sphere", "plane", "cube", "torus", "teapot", "dense_sphere"}; }

Result<MeshData> makeBuiltinMesh(const std::string& name) {
  if (name == "sphere") return makeUvSphere(128, 64);
  if (name == "plane") return makePlane();
  if (name == "cube") return makeCube();
  if (name == "torus") return makeTorus(0.7, 0.3, 128, 64);
  if (name == "teapot") return makeTeapot(16);
  // 512 x 500 segments: 512 * (2 * 500 - 2) = 510,976 triangles.
  if (name == "dense_sphere") return renamed(makeUvSphere(512, 500), "dense_sphere");
  return makeError(ErrorCode::NotFound, "unknown mesh '" + name + "'", "mesh");
}

}  // namespace brdfa
