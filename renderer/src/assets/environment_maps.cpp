#include "assets/environment_maps.h"

#include <glm/glm.hpp>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/packing.hpp>

#include <cmath>

namespace brdfa {

void cubeFaceDirection(int face, float s, float t, float dir[3]) {
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

void cubeTexelDirection(int face, uint32_t x, uint32_t y, uint32_t size, float dir[3]) {
  float s = 2.0f * (static_cast<float>(x) + 0.5f) / static_cast<float>(size) - 1.0f;
  float t = 2.0f * (static_cast<float>(y) + 0.5f) / static_cast<float>(size) - 1.0f;
  cubeFaceDirection(face, s, t, dir);
}

void cubeTexelStratumDirection(int face, uint32_t x, uint32_t y, uint32_t size, int i, int j, int n, float dir[3]) {
  float s = 2.0f * (static_cast<float>(x) + (i + 0.5f) / n) / static_cast<float>(size) - 1.0f;
  float t = 2.0f * (static_cast<float>(y) + (j + 0.5f) / n) / static_cast<float>(size) - 1.0f;
  cubeFaceDirection(face, s, t, dir);
}

namespace {

// Solid angle of the face region from the face centre to the point (s, t), signed:
// atan2(s t, sqrt(s^2 + t^2 + 1)). Texel solid angles are sums and differences of it at the
// texel's corners (Driscoll, "Cubemap Texel Solid Angle", rorydriscoll.com, 2012).
double areaElement(double s, double t) { return std::atan2(s * t, std::sqrt(s * s + t * t + 1.0)); }

}  // namespace

double cubeTexelSolidAngle(uint32_t x, uint32_t y, uint32_t size) {
  double inv = 2.0 / size;
  double s0 = x * inv - 1.0, s1 = s0 + inv;
  double t0 = y * inv - 1.0, t1 = t0 + inv;
  return areaElement(s0, t0) - areaElement(s0, t1) - areaElement(s1, t0) + areaElement(s1, t1);
}

void cubeFaceCoords(const float dir[3], int& face, float& s, float& t) {
  // The major axis picks the face; (sc, tc, ma) as in the Vulkan spec's face selection table.
  float ax = std::abs(dir[0]), ay = std::abs(dir[1]), az = std::abs(dir[2]);
  float sc, tc, ma;
  if (ax >= ay && ax >= az) {
    face = dir[0] >= 0.0f ? 0 : 1;
    sc = dir[0] >= 0.0f ? -dir[2] : dir[2];
    tc = -dir[1];
    ma = ax;
  } else if (ay >= az) {
    face = dir[1] >= 0.0f ? 2 : 3;
    sc = dir[0];
    tc = dir[1] >= 0.0f ? dir[2] : -dir[2];
    ma = ay;
  } else {
    face = dir[2] >= 0.0f ? 4 : 5;
    sc = dir[2] >= 0.0f ? dir[0] : -dir[0];
    tc = -dir[1];
    ma = az;
  }
  s = sc / ma;
  t = tc / ma;
}

HalfCube packHalfCube(const EnvironmentData& env) {
  constexpr float kHalfMax = 65504.0f;
  float brightest = 0.0f;
  for (size_t i = 0; i < env.texels.size(); i += 4)
    for (int c = 0; c < 3; ++c) brightest = std::max(brightest, env.texels[i + c]);
  HalfCube cube;
  // A power of two: dividing by it is exact, so texels within range pack exactly as before.
  while (brightest / cube.scale > kHalfMax) cube.scale *= 2.0f;
  cube.texels.resize(env.texels.size());
  for (size_t i = 0; i < env.texels.size(); i += 4) {
    for (int c = 0; c < 3; ++c) cube.texels[i + c] = glm::packHalf1x16(env.texels[i + c] / cube.scale);
    cube.texels[i + 3] = glm::packHalf1x16(1.0f);
  }
  return cube;
}

EnvironmentData makeFilteredCube(const std::string& name, uint32_t size, const DirectionLookup& lookup,
                                 const StrataPerAxis& strata) {
  EnvironmentData env;
  env.name = name;
  env.faceSize = size;
  env.texels.resize(size_t(6) * size * size * 4);
  float* out = env.texels.data();
  for (int face = 0; face < 6; ++face)
    for (uint32_t y = 0; y < size; ++y)
      for (uint32_t x = 0; x < size; ++x, out += 4) {
        int n = strata(face, x, y);
        double sum[3] = {0, 0, 0};
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i) {
            float d[3], rgb[3];
            cubeTexelStratumDirection(face, x, y, size, i, j, n, d);
            lookup(d, rgb);
            for (int c = 0; c < 3; ++c) sum[c] += rgb[c];
          }
        for (int c = 0; c < 3; ++c) out[c] = static_cast<float>(sum[c] / (n * n));
        out[3] = 1.0f;
      }
  return env;
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

// A rectangular area light seen from the origin: a flat rectangle at unit distance along
// `centre`, facing the origin, `tanHalfWidth` and `tanHalfHeight` wide in the gnomonic
// (tangent-plane) coordinates of its horizontal and vertical axes. Its edges are great-circle
// arcs, so a mirror reflection of it is a sharp, straight-edged rectangle.
struct RectLight {
  glm::vec3 centre;
  float tanHalfWidth, tanHalfHeight;
  glm::vec3 radiance;
};

bool insideRect(const RectLight& light, const glm::vec3& d) {
  glm::vec3 c = glm::normalize(light.centre);
  float dc = glm::dot(d, c);
  if (dc <= 0.0f) return false;  // the light's plane lies behind this direction
  // Horizontal axis of the rectangle: perpendicular to both +Y and the centre direction. No
  // light sits at the zenith, so the cross product is never near zero.
  glm::vec3 right = glm::normalize(glm::cross(c, glm::vec3(0, 1, 0)));
  glm::vec3 up = glm::cross(right, c);
  return std::abs(glm::dot(d, right) / dc) < light.tanHalfWidth && std::abs(glm::dot(d, up) / dc) < light.tanHalfHeight;
}

// A photo studio: a dim grey surround (0.03) and three area lights. The default camera sits
// at +Z looking down -Z, so the key light is at the camera's upper left, the fill at its right
// and lower, the rim a long strip above and behind the object. Irradiance at a surface facing
// each light is roughly radiance x solid angle, the solid angle of such a rectangle being
// 4 asin(a b / sqrt((1 + a^2)(1 + b^2))) for tangent half-sizes a, b: key 14 x 0.25 sr ~ 3.5,
// fill 2.2 x 0.55 sr ~ 1.2, rim 9 x 0.18 sr ~ 1.6, surround 0.03 x pi ~ 0.1.
glm::vec3 studioRadiance(const glm::vec3& d) {
  static const RectLight kLights[] = {
      {{-0.55f, 0.55f, 0.63f}, 0.32f, 0.21f, {14.0f, 13.3f, 12.0f}},  // key: warm, 35 x 24 degrees
      {{0.85f, 0.10f, 0.50f}, 0.40f, 0.40f, {2.0f, 2.2f, 2.6f}},      // fill: cool, 44 x 44 degrees
      {{0.15f, 0.45f, -0.88f}, 0.58f, 0.09f, {9.0f, 9.0f, 9.0f}},     // rim: a 60 x 10 degree strip
  };
  for (const RectLight& light : kLights)
    if (insideRect(light, d)) return light.radiance;
  return glm::vec3(0.03f);
}

// Inside a Cornell-box-like room: the box [-1, 1]^3 seen from its centre, red wall at -X (the
// default camera's left), green at +X, white elsewhere, and a square light in the ceiling.
// Light and albedos follow the classic scene (Bitterli, "Rendering Resources", cornell-box:
// emission (17, 12, 4); albedos white (0.725, 0.71, 0.68), red (0.63, 0.065, 0.05), green
// (0.14, 0.45, 0.091)). Walls are Lambertian with one constant irradiance E, so their radiance
// is albedo x E / pi. E: the light (half-size 0.25 at distance 2 from the floor) subtends about
// 0.5^2 / 2^2 = 0.0625 sr, direct E ~ 0.0625 x emission; interreflections add roughly half
// again, so E ~ 0.09 x emission.
glm::vec3 cornellRadiance(const glm::vec3& d) {
  const glm::vec3 emission(17.0f, 12.0f, 4.0f);
  const glm::vec3 white(0.725f, 0.71f, 0.68f), red(0.63f, 0.065f, 0.05f), green(0.14f, 0.45f, 0.091f);
  const glm::vec3 irradiance = 0.09f * emission;
  const float lightHalfSize = 0.25f;
  // The ray from the centre leaves the box through the wall of its largest coordinate.
  glm::vec3 a = glm::abs(d);
  glm::vec3 albedo = white;
  if (a.x >= a.y && a.x >= a.z) {
    albedo = d.x < 0.0f ? red : green;
  } else if (a.y >= a.z && d.y > 0.0f) {
    glm::vec3 hit = d / d.y;  // the point on the ceiling y = 1
    if (std::abs(hit.x) < lightHalfSize && std::abs(hit.z) < lightHalfSize) return emission;
  }
  return albedo * irradiance / glm::pi<float>();
}

using RadianceFn = glm::vec3 (*)(const glm::vec3&);

// `samples` x `samples` lookups per texel; 1 samples each texel's centre only.
EnvironmentData makeCube(const std::string& name, uint32_t size, RadianceFn radiance, int samples) {
  return makeFilteredCube(
      name, size,
      [radiance](const float dir[3], float rgb[3]) {
        glm::vec3 L = radiance(glm::vec3(dir[0], dir[1], dir[2]));
        rgb[0] = L.r;
        rgb[1] = L.g;
        rgb[2] = L.b;
      },
      [samples](int, uint32_t, uint32_t) { return samples; });
}

}  // namespace

std::vector<std::string> builtinEnvironmentNames() { return {"furnace", "sky", "studio", "cornell"}; }

Result<EnvironmentData> makeBuiltinEnvironment(const std::string& name) {
  if (name == "furnace") {
    // Constant radiance 1. Kernels compile the lookup out; the 1x1 map keeps bindings valid.
    EnvironmentData env = makeCube(
        name, 1, [](const glm::vec3&) { return glm::vec3(1.0f); }, 1);
    env.constant = true;
    return env;
  }
  if (name == "sky") return makeCube(name, 128, skyRadiance, 1);
  // 256 texels per face: a light's edge stays sharp in a mirror-like highlight.
  if (name == "studio") return makeCube(name, 256, studioRadiance, 2);
  if (name == "cornell") return makeCube(name, 256, cornellRadiance, 2);
  return makeError(ErrorCode::NotFound, "unknown environment '" + name + "'", "environment.name");
}

}  // namespace brdfa
