// Turning VkResult into the renderer's error values.
#pragma once

#include <vulkan/vulkan.h>

#include <string>

#include "brdfa/result.h"

namespace brdfa {

const char* vkResultName(VkResult r);

inline Error vkError(VkResult r, const char* what) {
  return makeError(ErrorCode::DeviceError, std::string(what) + " failed: " + vkResultName(r));
}

}  // namespace brdfa

// Returns an Error from the enclosing function (whose return type is a Result) on failure.
#define BRDFA_VK_TRY(call)                                                      \
  do {                                                                          \
    VkResult brdfa_vk_r_ = (call);                                              \
    if (brdfa_vk_r_ != VK_SUCCESS) return ::brdfa::vkError(brdfa_vk_r_, #call); \
  } while (0)
