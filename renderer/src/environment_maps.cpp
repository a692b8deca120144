#include "environment_maps.h"

#include <glm/glm.hpp>
#include <glm/gtc/packing.hpp>

#include <cmath>

namespace brdfa {

void cubeTexelDirection(int face, uint32_t x, uint32_t y, uint32_t size, float dir[3]) {
  float s = 2.0f * (static_cast<float>(x) + 0.5f) / static_cast<float>(size) - 1.0f;
  float t = 2.0f * (static_cast<float>(y) + 0.5f) / static_cast<float>(size) - 1.0f;
  glm::vec3 d;
  switch (face) {
    case 0: d = {1, -t, -s}; break;
    case 1: d = {-1, -t, s}; break;
    case 2: d = {s, 1, t}; break;
    case 3: d = {s, -1, -t}; break;
    case 4: d = {s, -t, 1}; break;
    default: d = {-s, -t, -1}; break;
  }
  d = glm::normalize(d);
  dir[0] = d.x;
  dir[1] = d.y;
  dir[2] = d.z;
}

namespace {

// A clear daytime sky with a sun: a zenith-to-horizon gradient, a dim ground, and a sun disk
// of radius 2.5 degrees at radiance 150 with a soft glow, so the map is truly HDR (the sun
// carries about as much irradiance as the whole sky dome).
glm::vec3 skyRadiance(const glm::vec3& d) {
  const glm::vec3 sunDir = glm::normalize(glm::vec3(-0.45f, 0.55f, 0.70f));
  const glm::vec3 zenith(0.25f, 0.45f, 0.95f), horizon(0.85f, 0.90f, 1.0f), ground(0.18f, 0.16f, 0.14f);
  float up = glm::clamp(d.y, -1.0f, 1.0f);
  glm::vec3 sky = glm::mix(horizon, zenith, std::pow(glm::max(up, 0.0f), 0.6f));
  // Blend into the ground over a narrow band below the horizon to avoid a hard seam.
  float groundWeight = glm::smoothstep(0.0f, -0.05f, up);
  glm::vec3 L = glm::mix(sky, ground, groundWeight);
  float c = glm::dot(d, sunDir);
  if (c > std::cos(glm::radians(2.5f))) L += glm::vec3(150.0f, 142.0f, 128.0f);
  L += glm::vec3(2.0f, 1.8f, 1.4f) * std::pow(glm::max(c, 0.0f), 64.0f);
  return L;
}

EnvironmentData makeCube(const std::string& name, uint32_t size, glm::vec3 (*radiance)(const glm::vec3&)) {
  EnvironmentData env;
  env.name = name;
  env.faceSize = size;
  env.texels.resize(size_t(6) * size * size * 4);
  size_t i = 0;
  for (int face = 0; face < 6; ++face)
    for (uint32_t y = 0; y < size; ++y)
      for (uint32_t x = 0; x < size; ++x) {
        float d[3];
        cubeTexelDirection(face, x, y, size, d);
        glm::vec3 L = radiance(glm::vec3(d[0], d[1], d[2]));
        env.texels[i++] = glm::packHalf1x16(L.r);
        env.texels[i++] = glm::packHalf1x16(L.g);
        env.texels[i++] = glm::packHalf1x16(L.b);
        env.texels[i++] = glm::packHalf1x16(1.0f);
      }
  return env;
}

}  // namespace

std::vector<std::string> builtinEnvironmentNames() { return {"furnace", "sky"}; }

Result<EnvironmentData> makeBuiltinEnvironment(const std::string& name) {
  if (name == "furnace") {
    // Constant radiance 1. Kernels compile the lookup out; the 1x1 map keeps bindings valid.
    EnvironmentData env = makeCube(name, 1, [](const glm::vec3&) { return glm::vec3(1.0f); });
    env.constant = true;
    return env;
  }
  if (name == "sky") return makeCube(name, 128, skyRadiance);
  return makeError(ErrorCode::NotFound, "unknown environment '" + name + "'", "environment.name");
}

}  // namespace brdfa
