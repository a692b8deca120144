// Device-side forms of meshes, environments and textures, shared between views.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "assets/environment_sampling.h"
#include "core/memory_ledger.h"
#include "device/vk_resources.h"

namespace brdfa {

struct GpuMesh {
  std::string name;
  float boundsMin[3] = {0, 0, 0};  // object-space bounding box
  float boundsMax[3] = {0, 0, 0};
  Buffer vertices;
  Buffer indices;
  uint32_t vertexCount = 0;
  uint32_t indexCount = 0;
  MemoryReservation memory;  // its share of the renderer's memory budget
};

struct GpuEnvironment {
  std::string name;
  bool constant = false;
  float scale = 1.0f;  // radiance = texel * scale (packHalfCube); folded into the intensity push constant
  Image cube;          // RGBA16F, SHADER_READ_ONLY_OPTIMAL
  // Importance-sampling table (environment_sampling.h): a uniform texel buffer of RG32UI
  // entries, read with texelFetch at set 0 binding 9. Its reads are random, and on a CPU device
  // (lavapipe) they were most of a mis sample's cost: a texel buffer's fetch skips the 2D
  // addressing of an image, and 64-bit entries cost less than 128-bit ones (bench --only
  // sampling compares them). A constant environment has only the header.
  TexelBuffer table;
  std::shared_ptr<const EnvironmentDistribution> distribution;  // the same table on the host; null when constant
  MemoryReservation memory;                                     // its share of the renderer's memory budget
};

// A texture an object samples as iTexture0..3: RGBA8, sRGB-decoding or linear.
struct GpuTexture {
  std::string name;
  bool srgb = true;
  Image image;               // SHADER_READ_ONLY_OPTIMAL
  MemoryReservation memory;  // its share of the renderer's memory budget
};

// A measured BRDF's table (brdfa/measured.h's MeasuredTable: 3 floats per bin) as the storage
// buffer a measured program reads at set 1, binding 6.
struct GpuMeasured {
  std::string name;
  Buffer table;              // device-local
  MemoryReservation memory;  // its share of the renderer's memory budget
};

}  // namespace brdfa
