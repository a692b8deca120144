// The descriptor set and pipeline layouts every program of the renderer is built against, and
// the G-buffer's render pass (bindings as in shaders/lib/bindings.glsl).
#pragma once

#include <vulkan/vulkan.h>

#include <set>

#include "brdfa/result.h"

#include "programs/spirv_resources.h"

namespace brdfa {

// The G-buffer's two planes (shaders/lib/bindings.glsl): surface = object id and normal,
// detail = tangent and texCoord; bytes per pixel below.
constexpr VkFormat kGbufferSurfaceFormat = VK_FORMAT_R32G32_UINT;
constexpr VkFormat kGbufferDetailFormat = VK_FORMAT_R32G32B32A32_UINT;
constexpr VkDeviceSize kGbufferSurfaceBytes = 8, kGbufferDetailBytes = 16;

class PipelineLayouts {
 public:
  explicit PipelineLayouts(VkDevice device) : device_(device) {}
  ~PipelineLayouts();
  PipelineLayouts(const PipelineLayouts&) = delete;
  PipelineLayouts& operator=(const PipelineLayouts&) = delete;
  Result<void> create();

  // Set 0: one view's G-buffer, accumulators, counters, environment and outputs.
  VkDescriptorSetLayout viewSet() const { return viewSetLayout_; }
  // Set 1: one object's BRDF parameters, transform and textures.
  VkDescriptorSetLayout objectSet() const { return objectSetLayout_; }
  VkPipelineLayout compute() const { return computeLayout_; }  // both sets, ComputePush
  VkPipelineLayout raster() const { return rasterLayout_; }    // both sets, mat4 viewProj
  VkRenderPass gbufferPass() const { return gbufferPass_; }
  // The slots a compute program may declare: what a BRDF's text adds beyond them is refused.
  const std::set<DescriptorSlot>& computeSlots() const { return computeSlots_; }

 private:
  VkDevice device_;
  VkDescriptorSetLayout viewSetLayout_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout objectSetLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout computeLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout rasterLayout_ = VK_NULL_HANDLE;
  VkRenderPass gbufferPass_ = VK_NULL_HANDLE;
  std::set<DescriptorSlot> computeSlots_;
};

}  // namespace brdfa
