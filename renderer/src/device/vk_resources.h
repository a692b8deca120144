// RAII owners for Vulkan buffers and images (moved, never copied).
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <utility>

#include "brdfa/result.h"

#include "device/vk_context.h"

namespace brdfa {

class Buffer {
 public:
  Buffer() = default;
  ~Buffer() { reset(); }
  Buffer(Buffer&& o) noexcept { *this = std::move(o); }
  Buffer& operator=(Buffer&& o) noexcept;

  // Host-visible buffers are persistently mapped (mapped() != nullptr) and host-coherent, in
  // host-cached memory where there is one, or device-local memory with `preferDeviceLocal`
  // (what the device reads often and the host writes once).
  static Result<Buffer> create(VkContext& ctx, VkDeviceSize size, VkBufferUsageFlags usage, bool hostVisible,
                               bool preferDeviceLocal = false);

  VkBuffer handle() const { return buffer_; }
  VkDeviceSize size() const { return size_; }
  void* mapped() const { return mapped_; }
  void reset();

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkDeviceSize size_ = 0;
  void* mapped_ = nullptr;
};

// A view of part of another Buffer as texels of `format` (for a samplerBuffer, usamplerBuffer or
// imageBuffer). The buffer must outlive the view; `offset` must be a multiple of the device's
// minTexelBufferOffsetAlignment.
class TexelView {
 public:
  TexelView() = default;
  ~TexelView() { reset(); }
  TexelView(TexelView&& o) noexcept { *this = std::move(o); }
  TexelView& operator=(TexelView&& o) noexcept;

  static Result<TexelView> create(VkContext& ctx, const Buffer& buffer, VkFormat format, VkDeviceSize offset,
                                  VkDeviceSize range);

  VkBufferView view() const { return view_; }
  void reset();

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  VkBufferView view_ = VK_NULL_HANDLE;
};

// A read-only uniform texel buffer: memory the host fills once at creation, seen by shaders
// through a view of `format` (a samplerBuffer / usamplerBuffer read with texelFetch).
class TexelBuffer {
 public:
  TexelBuffer() = default;
  ~TexelBuffer() { reset(); }
  TexelBuffer(TexelBuffer&& o) noexcept { *this = std::move(o); }
  TexelBuffer& operator=(TexelBuffer&& o) noexcept;

  static Result<TexelBuffer> create(VkContext& ctx, const void* data, VkDeviceSize bytes, VkFormat format);

  VkBufferView view() const { return view_.view(); }
  void reset();

 private:
  Buffer buffer_;
  TexelView view_;  // declared after buffer_: destroyed before it
};

struct ImageSpec {
  uint32_t width = 1, height = 1;
  uint32_t layers = 1;  // 6 with `cube`
  bool cube = false;
  VkFormat format = VK_FORMAT_R32G32B32A32_SFLOAT;
  VkImageUsageFlags usage = 0;
  VkImageAspectFlags aspect = VK_IMAGE_ASPECT_COLOR_BIT;
};

class Image {
 public:
  Image() = default;
  ~Image() { reset(); }
  Image(Image&& o) noexcept { *this = std::move(o); }
  Image& operator=(Image&& o) noexcept;

  static Result<Image> create(VkContext& ctx, const ImageSpec& spec);

  VkImage handle() const { return image_; }
  VkImageView view() const { return view_; }
  const ImageSpec& spec() const { return spec_; }
  void reset();

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  VkImage image_ = VK_NULL_HANDLE;
  VkImageView view_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  ImageSpec spec_;
};

// A command pool with one primary command buffer and a fence, for one thread at a time.
class CommandContext {
 public:
  CommandContext() = default;
  ~CommandContext() { reset(); }
  CommandContext(CommandContext&& o) noexcept { *this = std::move(o); }
  CommandContext& operator=(CommandContext&& o) noexcept;

  static Result<CommandContext> create(VkContext& ctx);

  // Resets and begins recording.
  Result<VkCommandBuffer> begin();
  // Ends recording, submits and waits for completion; `busyMs`: see VkContext::submitAndWait.
  // `viewPass`: a view's pass, which the queue counts as that view's use of it (see
  // VkContext::submissionTargetMs).
  Result<void> submitAndWait(double* busyMs = nullptr, bool viewPass = false);
  VkFence fence() const { return fence_; }  // identifies this context's submissions
  void reset();

 private:
  VkContext* ctx_ = nullptr;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer commands_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
};

// Records a global memory barrier between two pipeline stages.
void memoryBarrier(VkCommandBuffer cb, VkPipelineStageFlags src, VkAccessFlags srcAccess, VkPipelineStageFlags dst,
                   VkAccessFlags dstAccess);

// Records a layout transition of all subresources of `image`.
void imageBarrier(VkCommandBuffer cb, const Image& image, VkImageLayout from, VkImageLayout to,
                  VkPipelineStageFlags src, VkAccessFlags srcAccess, VkPipelineStageFlags dst, VkAccessFlags dstAccess);

// Uploads tightly packed texels to every layer of `image` (layer-major) and leaves it in
// SHADER_READ_ONLY_OPTIMAL.
Result<void> uploadImage(VkContext& ctx, const Image& image, const void* texels, VkDeviceSize bytes);

}  // namespace brdfa
