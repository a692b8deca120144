// The one Vulkan instance, device and queue of the process.
#pragma once

#include <vulkan/vulkan.h>

#include <condition_variable>
#include <chrono>
#include <deque>
#include <unordered_map>
#include <cstdint>
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

  // Submits one command buffer and waits on `fence`. The queue is shared by every view and
  // taken in turns, in arrival order, from the submission until its fence signals: so a view
  // whose pass is split into several submissions lets every view that asked meanwhile go in
  // between, and `busyMs` (optional) is this submission's own device time. (Released right
  // after vkQueueSubmit, lavapipe's queue thread would still run submissions in order, but the
  // wait would include the others' work; lavapipe's timestamp queries read ~0 for long
  // dispatches.) Recording, on the host, still runs concurrently.
  Result<void> submitAndWait(VkCommandBuffer commands, VkFence fence, double* busyMs = nullptr, bool viewPass = false);

  // Device time one submission of a pass aims at (RendererOptions::submissionTargetMs), or,
  // when no other view's pass (submissions with viewPass, told apart by their fence; `mine`
  // is the asking view's) used the queue in the last half second and nothing waits for it,
  // RendererOptions::soloSubmissionTargetMs (if larger).
  double submissionTargetMs(VkFence mine) const;

 private:
  VkContext() = default;
  void noteSubmission(VkFence fence);  // queueMutex_ held
  VkInstance instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queueFamily_ = 0;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  DeviceInfo info_;
  uint32_t subgroupSize_ = 1;
  double submissionTargetMs_ = 0;
  double soloSubmissionTargetMs_ = 0;
  // The queue's turn (see submitAndWait): first come, first served, rather than a mutex held
  // through the wait, since a view that submits again right after its fence signals would
  // usually win a plain mutex back before a waiting thread wakes up, and starve the others.
  // Each waiter has its own condition variable and only the next one is woken: with 30
  // sessions, waking all of them at every hand-over cost 2 cores a fifth of the throughput.
  mutable std::mutex queueMutex_;
  // When each fence's submission last held or waited for the queue (pruned past a second).
  std::unordered_map<VkFence, std::chrono::steady_clock::time_point> lastSubmission_;
  std::deque<std::condition_variable*> queueWaiters_;  // in arrival order
  bool queueBusy_ = false;                             // a submission holds the turn
};

}  // namespace brdfa
