// Built-in environments, generated on the CPU into one internal form: an RGBA16F cubemap.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "brdfa/result.h"

namespace brdfa {

struct EnvironmentData {
  std::string name;
  bool constant = false;     // radiance 1 in every direction (the furnace): kernels skip lookups
  uint32_t faceSize = 1;
  std::vector<uint16_t> texels;  // RGBA half floats, faces +X -X +Y -Y +Z -Z, rows top to bottom
};

std::vector<std::string> builtinEnvironmentNames();

// NotFound for an unknown name.
Result<EnvironmentData> makeBuiltinEnvironment(const std::string& name);

// World direction through the centre of texel (x, y) of cube face `face` (Vulkan/GL convention).
void cubeTexelDirection(int face, uint32_t x, uint32_t y, uint32_t size, float dir[3]);

}  // namespace brdfa
