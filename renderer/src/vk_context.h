// The one Vulkan instance, device and queue of the process.
#pragma once

#include <vulkan/vulkan.h>

#include <memory>
#include <mutex>
#include <string>

#include "brdfa/renderer.h"
#include "brdfa/result.h"

namespace brdfa {

class VkContext {
 public:
  // Picks options.deviceName when given (substring match, NotFound otherwise), else the first
  // discrete GPU, then integrated, then virtual, then CPU. Needs one queue with graphics+compute
  // and subgroup arithmetic in compute shaders (every Vulkan 1.1 GPU and lavapipe have it).
  static Result<std::unique_ptr<VkContext>> create(const RendererOptions& options);
  ~VkContext();
  VkContext(const VkContext&) = delete;
  VkContext& operator=(const VkContext&) = delete;

  VkDevice device() const { return device_; }
  VkPhysicalDevice physicalDevice() const { return physical_; }
  uint32_t queueFamily() const { return queueFamily_; }
  const DeviceInfo& info() const { return info_; }
  const VkPhysicalDeviceLimits& limits() const { return properties_.limits; }
  uint32_t subgroupSize() const { return subgroupSize_; }

  // A memory type in `typeBits` with all of `required`; prefers one that also has `preferred`.
  Result<uint32_t> findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required,
                                  VkMemoryPropertyFlags preferred = 0) const;

  // Submits one command buffer (the queue is shared by every view: submission is serialized)
  // and waits on `fence` outside the queue lock, so views render concurrently.
  Result<void> submitAndWait(VkCommandBuffer commands, VkFence fence);

 private:
  VkContext() = default;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queueFamily_ = 0;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  DeviceInfo info_;
  uint32_t subgroupSize_ = 1;
  std::mutex queueMutex_;
};

}  // namespace brdfa
