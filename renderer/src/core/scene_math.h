// Camera and object transforms, in one place for the raster pass and the compute kernels.
#pragma once

#include <glm/glm.hpp>

#include "brdfa/scene.h"

namespace brdfa {

struct CameraFrame {
  glm::vec3 position;
  glm::vec3 forward, right, up;  // unit, right-handed, +Y world up
  float tanHalfFov;
  float aspect;
  glm::mat4 viewProj;  // Vulkan clip space, Y flipped so row 0 of the image is the top
};

// yaw turns toward -X (counter-clockwise seen from above); pitch is clamped to +-89 degrees so
// the frame never degenerates.
CameraFrame cameraFrame(const Camera& camera, uint32_t width, uint32_t height);

// translate * rotateZ * rotateY * rotateX * scale (rotation about X is applied first).
glm::mat4 modelMatrix(const SceneObject& object);

// Pixels an object can cover: the screen rectangle of its transformed bounding box, plus a
// pixel of margin. The whole image when a corner is behind the camera (no safe projection).
struct PixelRect {
  uint32_t x = 0, y = 0, width = 0, height = 0;
};
// The smallest rectangle holding both (an empty rectangle adds nothing).
PixelRect unionRect(const PixelRect& a, const PixelRect& b);

// Sub-pixel offsets (in pixels, within +-0.5) of the anti-aliasing slices: a rotated grid of
// four (RGSS), or the pixel centre when `count` is 1.
glm::vec2 jitterOffset(uint32_t slice, uint32_t count);

// `viewProj` moved on screen by `offset` pixels (a clip-space translation proportional to w).
glm::mat4 jitteredViewProj(const glm::mat4& viewProj, glm::vec2 offset, uint32_t width, uint32_t height);

PixelRect screenBounds(const glm::mat4& viewProj, const glm::mat4& model, const float boundsMin[3],
                       const float boundsMax[3], uint32_t width, uint32_t height);

}  // namespace brdfa
