#include "scene_math.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace brdfa {

CameraFrame cameraFrame(const Camera& camera, uint32_t width, uint32_t height) {
  CameraFrame f;
  float yaw = glm::radians(camera.yaw);
  float pitch = glm::radians(std::clamp(camera.pitch, -89.0f, 89.0f));
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

}  // namespace brdfa
