#include "meshes.h"

#include <glm/glm.hpp>

#include <cmath>

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

std::vector<std::string> builtinMeshNames() { return {"sphere"}; }

Result<MeshData> makeBuiltinMesh(const std::string& name) {
  if (name == "sphere") return makeUvSphere(128, 64);
  return makeError(ErrorCode::NotFound, "unknown mesh '" + name + "'", "mesh");
}

}  // namespace brdfa
