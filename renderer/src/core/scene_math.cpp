#include "core/scene_math.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace brdfa {

CameraFrame cameraFrame(const Camera& camera, uint32_t width, uint32_t height) {
  CameraFrame f;
  float yaw = glm::radians(camera.yaw);
  float pitch = glm::radians(std::clamp(camera.pitch, -kMaxPitch, kMaxPitch));
  f.position = glm::vec3(camera.position[0], camera.position[1], camera.position[2]);
  f.forward = glm::vec3(-std::sin(yaw) * std::cos(pitch), std::sin(pitch), -std::cos(yaw) * std::cos(pitch));
  f.right = glm::normalize(glm::cross(f.forward, glm::vec3(0, 1, 0)));
  f.up = glm::cross(f.right, f.forward);
  f.tanHalfFov = std::tan(glm::radians(camera.fov) * 0.5f);
  f.aspect = static_cast<float>(width) / static_cast<float>(height);
  glm::mat4 view = glm::lookAt(f.position, f.position + f.forward, f.up);
  glm::mat4 proj = glm::perspective(glm::radians(camera.fov), f.aspect, 0.01f, 1000.0f);
  proj[1][1] *= -1.0f;  // Vulkan's clip-space Y points down
  f.viewProj = proj * view;
  return f;
}

glm::mat4 modelMatrix(const SceneObject& o) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(o.translate[0], o.translate[1], o.translate[2]));
  m = glm::rotate(m, glm::radians(o.rotate[2]), glm::vec3(0, 0, 1));
  m = glm::rotate(m, glm::radians(o.rotate[1]), glm::vec3(0, 1, 0));
  m = glm::rotate(m, glm::radians(o.rotate[0]), glm::vec3(1, 0, 0));
  return glm::scale(m, glm::vec3(o.scale[0], o.scale[1], o.scale[2]));
}

PixelRect screenBounds(const glm::mat4& viewProj, const glm::mat4& model, const float boundsMin[3],
                       const float boundsMax[3], uint32_t width, uint32_t height) {
  const PixelRect whole{0, 0, width, height};
  float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    glm::vec4 local((corner & 1) ? boundsMax[0] : boundsMin[0], (corner & 2) ? boundsMax[1] : boundsMin[1],
                    (corner & 4) ? boundsMax[2] : boundsMin[2], 1.0f);
    glm::vec4 clip = viewProj * (model * local);
    if (clip.w <= 1e-4f) return whole;  // behind or at the camera plane
    float px = (clip.x / clip.w * 0.5f + 0.5f) * static_cast<float>(width);
    float py = (clip.y / clip.w * 0.5f + 0.5f) * static_cast<float>(height);
    x0 = std::min(x0, px);
    x1 = std::max(x1, px);
    y0 = std::min(y0, py);
    y1 = std::max(y1, py);
  }
  const float w = static_cast<float>(width), h = static_cast<float>(height);
  x0 = std::clamp(std::floor(x0) - 1.0f, 0.0f, w);
  y0 = std::clamp(std::floor(y0) - 1.0f, 0.0f, h);
  x1 = std::clamp(std::ceil(x1) + 1.0f, 0.0f, w);
  y1 = std::clamp(std::ceil(y1) + 1.0f, 0.0f, h);
  return PixelRect{static_cast<uint32_t>(x0), static_cast<uint32_t>(y0), static_cast<uint32_t>(x1 - x0),
                   static_cast<uint32_t>(y1 - y0)};
}

PixelRect unionRect(const PixelRect& a, const PixelRect& b) {
  if (a.width == 0 || a.height == 0) return b;
  if (b.width == 0 || b.height == 0) return a;
  const uint32_t x0 = std::min(a.x, b.x), y0 = std::min(a.y, b.y);
  const uint32_t x1 = std::max(a.x + a.width, b.x + b.width), y1 = std::max(a.y + a.height, b.y + b.height);
  return PixelRect{x0, y0, x1 - x0, y1 - y0};
}

glm::vec2 jitterOffset(uint32_t slice, uint32_t count) {
  if (count <= 1) return glm::vec2(0.0f);
  // Rotated-grid supersampling: four points whose x and y projections are all distinct, which
  // resolves near-horizontal and near-vertical edges into 4 levels instead of 2.
  static const glm::vec2 kRotatedGrid[4] = {{0.125f, 0.375f}, {0.375f, -0.125f}, {-0.125f, -0.375f}, {-0.375f, 0.125f}};
  return kRotatedGrid[slice % 4];
}

glm::mat4 jitteredViewProj(const glm::mat4& viewProj, glm::vec2 offset, uint32_t width, uint32_t height) {
  // x_ndc += 2 dx / width  <=>  x_clip += (2 dx / width) w_clip: a translation applied after the
  // projection (its w column scales with w_clip).
  glm::mat4 shift(1.0f);
  shift[3][0] = 2.0f * offset.x / static_cast<float>(width);
  shift[3][1] = 2.0f * offset.y / static_cast<float>(height);
  return shift * viewProj;
}

}  // namespace brdfa
