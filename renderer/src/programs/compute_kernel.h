// Compiled compute programs on the device, and the push constants and per-object uniform they
// share with the shaders (shaders/lib/bindings.glsl, gbuffer.vert.glsl).
#pragma once

#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <memory>

#include "core/memory_ledger.h"
#include "programs/program_assembler.h"

namespace brdfa {

// A compute pipeline that owns its VkPipeline.
class ComputeKernel {
 public:
  ComputeKernel(VkDevice device, VkPipeline pipeline) : device_(device), pipeline_(pipeline) {}
  ~ComputeKernel() {
    if (pipeline_) vkDestroyPipeline(device_, pipeline_, nullptr);
  }
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
  // does at the first dispatch, is behind it (ProgramCache::compilesAtFirstDispatch).
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
