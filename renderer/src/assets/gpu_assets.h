// Device-side forms of meshes, environments and compiled kernels, shared between views.
#pragma once

#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "assets/environment_sampling.h"
#include "core/memory_ledger.h"
#include "device/vk_resources.h"
#include "programs/program_assembler.h"

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
  Image cube;  // RGBA16F, SHADER_READ_ONLY_OPTIMAL
  // Importance-sampling table (environment_sampling.h): a uniform texel buffer of RG32UI
  // entries, read with texelFetch at set 0 binding 9. Its reads are random, and on a CPU device
  // (lavapipe) they were most of a mis sample's cost: a texel buffer's fetch skips the 2D
  // addressing of an image, and 64-bit entries cost less than 128-bit ones (bench --only
  // sampling: mis at 38-45 % of cosine's samples/s with an RGBA32F image, 51-54 % with an
  // RG32UI image, 54-57 % with this buffer). A constant environment has only the header.
  TexelBuffer table;
  std::shared_ptr<const EnvironmentDistribution> distribution;  // the same table on the host; null when constant
  MemoryReservation memory;  // its share of the renderer's memory budget
};

// A texture an object samples as iTexture0..3: RGBA8, sRGB-decoding or linear.
struct GpuTexture {
  std::string name;
  bool srgb = true;
  Image image;  // SHADER_READ_ONLY_OPTIMAL
  MemoryReservation memory;  // its share of the renderer's memory budget
};

// A compute pipeline that owns its VkPipeline.
class ComputeKernel {
 public:
  ComputeKernel(VkDevice device, VkPipeline pipeline) : device_(device), pipeline_(pipeline) {}
  ~ComputeKernel() { if (pipeline_) vkDestroyPipeline(device_, pipeline_, nullptr); }
  ComputeKernel(const ComputeKernel&) = delete;
  ComputeKernel& operator=(const ComputeKernel&) = delete;
  VkPipeline pipeline() const { return pipeline_; }

 private:
  VkDevice device_;
  VkPipeline pipeline_;
};

// The integrator specialized to one BRDF and one variant (sampling mode, environment kind).
struct ShadeKernel {
  std::unique_ptr<ComputeKernel> kernel;
  ParamBlockLayout params;
  uint64_t programHash = 0;  // hash of the assembled source: identifies the compiled program
  uint64_t spirvBytes = 0;   // size of its SPIR-V (what specialization saves shows here)
  MemoryReservation memory;  // its share of the renderer's memory budget
  // A submission that dispatched it has completed: the driver's compile, which a CPU device
  // does at the first dispatch, is behind it (RendererImpl::compilesAtFirstDispatch).
  mutable std::atomic<bool> dispatched{false};
};

// Push constants of every compute kernel; mirrors BrdfaPush in shaders/lib/bindings.glsl.
struct ComputePush {
  float cameraPos[4];
  float cameraRight[4];
  float cameraUp[4];
  float cameraForward[4];
  float env[4];
  uint32_t frame[4];
  uint32_t target[4];
  float tone[4];
};
static_assert(sizeof(ComputePush) == 128, "push constants must fit the 128-byte minimum");

// Per-object uniform of the raster pass; mirrors BrdfaObject in gbuffer.vert.glsl.
struct ObjectUniform {
  float model[16];
  float normalMatrix[16];
  float id[4];
};

}  // namespace brdfa
