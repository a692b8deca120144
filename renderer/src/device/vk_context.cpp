#include "device/vk_context.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <optional>
#include <vector>

#include "device/device_activity.h"
#include "device/vk_check.h"

namespace brdfa {

const char* vkResultName(VkResult r) {
  switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    default: return "VkResult error";
  }
}

namespace {

int typeRank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

bool findQueueFamily(VkPhysicalDevice pd, uint32_t& family) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> props(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, props.data());
  const VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
  for (uint32_t i = 0; i < n; ++i) {
    if ((props[i].queueFlags & need) == need) {
      family = i;
      return true;
    }
  }
  return false;
}

std::string versionString(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
         std::to_string(VK_API_VERSION_PATCH(v));
}

bool hasLayer(const char* name) {
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  return std::any_of(layers.begin(), layers.end(),
                     [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

}  // namespace

Result<std::unique_ptr<VkContext>> VkContext::create(const RendererOptions& options) {
  std::unique_ptr<VkContext> ctx(new VkContext());

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "brdfa";
  app.apiVersion = VK_API_VERSION_1_1;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pApplicationInfo = &app;
  const char* validation = "VK_LAYER_KHRONOS_validation";
  if (options.validation && hasLayer(validation)) {
    ici.enabledLayerCount = 1;
    ici.ppEnabledLayerNames = &validation;
  }
  BRDFA_VK_TRY(vkCreateInstance(&ici, nullptr, &ctx->instance_));

  uint32_t count = 0;
  BRDFA_VK_TRY(vkEnumeratePhysicalDevices(ctx->instance_, &count, nullptr));
  std::vector<VkPhysicalDevice> devices(count);
  BRDFA_VK_TRY(vkEnumeratePhysicalDevices(ctx->instance_, &count, devices.data()));

  VkPhysicalDevice chosen = VK_NULL_HANDLE;
  int bestRank = 1 << 30;
  std::string seen;
  for (VkPhysicalDevice pd : devices) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pd, &p);
    uint32_t family;
    if (!findQueueFamily(pd, family)) continue;
    seen += std::string(seen.empty() ? "" : ", ") + p.deviceName;
    if (!options.deviceName.empty()) {
      if (std::string(p.deviceName).find(options.deviceName) != std::string::npos) {
        chosen = pd;
        break;
      }
      continue;
    }
    if (typeRank(p.deviceType) < bestRank) {
      bestRank = typeRank(p.deviceType);
      chosen = pd;
    }
  }
  if (chosen == VK_NULL_HANDLE) {
    return makeError(options.deviceName.empty() ? ErrorCode::DeviceError : ErrorCode::NotFound,
                     options.deviceName.empty()
                         ? "no Vulkan device with a graphics+compute queue (is mesa-vulkan-drivers installed?)"
                         : "no Vulkan device matches '" + options.deviceName + "'; available: " + seen);
  }
  ctx->physical_ = chosen;
  findQueueFamily(chosen, ctx->queueFamily_);
  vkGetPhysicalDeviceProperties(chosen, &ctx->properties_);
  vkGetPhysicalDeviceMemoryProperties(chosen, &ctx->memory_);

  float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = ctx->queueFamily_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  BRDFA_VK_TRY(vkCreateDevice(chosen, &dci, nullptr, &ctx->device_));
  vkGetDeviceQueue(ctx->device_, ctx->queueFamily_, 0, &ctx->queue_);

  // The driver name and version come from VkPhysicalDeviceDriverProperties (core in 1.2).
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props2.pNext = &subgroup;
  if (ctx->properties_.apiVersion >= VK_API_VERSION_1_2) subgroup.pNext = &driver;
  vkGetPhysicalDeviceProperties2(chosen, &props2);
  const VkSubgroupFeatureFlags needOps = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_ARITHMETIC_BIT;
  if (ctx->properties_.apiVersion < VK_API_VERSION_1_1 || !(subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) ||
      (subgroup.supportedOperations & needOps) != needOps)
    return makeError(ErrorCode::Unsupported, std::string(ctx->properties_.deviceName) +
                                                 ": needs Vulkan 1.1 subgroup arithmetic in compute shaders");
  ctx->subgroupSize_ = subgroup.subgroupSize;
  ctx->submissionTargetMs_ = std::max(0.0, options.submissionTargetMs);
  ctx->soloSubmissionTargetMs_ = std::max(0.0, options.soloSubmissionTargetMs);

  const auto& p = ctx->properties_;
  ctx->info_.name = p.deviceName;
  ctx->info_.type = p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU ? "cpu" : "gpu";
  ctx->info_.apiVersion = versionString(p.apiVersion);
  ctx->info_.driver = p.apiVersion >= VK_API_VERSION_1_2 ? std::string(driver.driverName) + " " + driver.driverInfo
                                                         : "driver " + std::to_string(p.driverVersion);
  return ctx;
}

VkContext::~VkContext() {
  if (device_) {
    vkDeviceWaitIdle(device_);
    vkDestroyDevice(device_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
}

Result<uint32_t> VkContext::findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required,
                                           VkMemoryPropertyFlags preferred) const {
  int fallback = -1;
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
    if (!(typeBits & (1u << i))) continue;
    VkMemoryPropertyFlags f = memory_.memoryTypes[i].propertyFlags;
    if ((f & required) != required) continue;
    if ((f & preferred) == preferred) return i;
    if (fallback < 0) fallback = static_cast<int>(i);
  }
  if (fallback >= 0) return static_cast<uint32_t>(fallback);
  return makeError(ErrorCode::DeviceError, "no suitable Vulkan memory type");
}

namespace {
constexpr auto kOthersWindow = std::chrono::milliseconds(500);
}  // namespace

void VkContext::noteSubmission(VkFence fence) {
  const auto now = std::chrono::steady_clock::now();
  lastSubmission_[fence] = now;
  if (lastSubmission_.size() > 64)
    std::erase_if(lastSubmission_, [&](const auto& e) { return now - e.second > std::chrono::seconds(1); });
}

double VkContext::submissionTargetMs(VkFence mine) const {
  if (submissionTargetMs_ <= 0 || soloSubmissionTargetMs_ <= submissionTargetMs_) return submissionTargetMs_;
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard lock(queueMutex_);
  const bool othersWaiting = !queueWaiters_.empty();
  for (const auto& [fence, when] : lastSubmission_)
    if (fence != mine && now - when < kOthersWindow) return submissionTargetMs_;
  return othersWaiting ? submissionTargetMs_ : soloSubmissionTargetMs_;
}

Result<void> VkContext::submitAndWait(VkCommandBuffer commands, VkFence fence, double* busyMs, bool viewPass) {
  BRDFA_VK_TRY(vkResetFences(device_, 1, &fence));
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &commands;
  // In flight from its place in the queue's order until its fence signals (device_activity.h).
  std::optional<device_activity::Scope> inFlight;
  std::unique_lock<std::mutex> lock(queueMutex_);
  if (viewPass) noteSubmission(fence);
  if (queueBusy_ || !queueWaiters_.empty()) {
    std::condition_variable turn;
    queueWaiters_.push_back(&turn);
    turn.wait(lock, [&] { return !queueBusy_ && queueWaiters_.front() == &turn; });
    queueWaiters_.pop_front();
  }
  queueBusy_ = true;
  inFlight.emplace(device_activity::Kind::Submission);
  lock.unlock();
  const auto start = std::chrono::steady_clock::now();
  VkResult r = vkQueueSubmit(queue_, 1, &si, fence);
  const char* what = "vkQueueSubmit";
  if (r == VK_SUCCESS) {
    r = vkWaitForFences(device_, 1, &fence, VK_TRUE, UINT64_MAX);
    what = "vkWaitForFences";
  }
  if (busyMs) *busyMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  lock.lock();
  if (viewPass) noteSubmission(fence);
  queueBusy_ = false;
  if (!queueWaiters_.empty()) queueWaiters_.front()->notify_one();
  lock.unlock();
  if (r != VK_SUCCESS) return vkError(r, what);
  return {};
}

}  // namespace brdfa
