#include "device/vk_resources.h"

#include <cstring>

#include "device/vk_check.h"

namespace brdfa {

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    reset();
    std::swap(device_, o.device_);
    std::swap(buffer_, o.buffer_);
    std::swap(memory_, o.memory_);
    std::swap(size_, o.size_);
    std::swap(mapped_, o.mapped_);
  }
  return *this;
}

void Buffer::reset() {
  if (!device_) return;
  if (buffer_) vkDestroyBuffer(device_, buffer_, nullptr);
  if (memory_) vkFreeMemory(device_, memory_, nullptr);  // unmaps implicitly
  device_ = VK_NULL_HANDLE;
  buffer_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
  size_ = 0;
}

Result<Buffer> Buffer::create(VkContext& ctx, VkDeviceSize size, VkBufferUsageFlags usage, bool hostVisible,
                              bool preferDeviceLocal) {
  Buffer b;
  b.device_ = ctx.device();
  b.size_ = size;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = size;
  bci.usage = usage;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  BRDFA_VK_TRY(vkCreateBuffer(b.device_, &bci, nullptr, &b.buffer_));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(b.device_, b.buffer_, &req);
  auto type = hostVisible
                  ? ctx.findMemoryType(
                        req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                        preferDeviceLocal ? VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT : VK_MEMORY_PROPERTY_HOST_CACHED_BIT)
                  : ctx.findMemoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  if (!type) return type.takeError();
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = *type;
  BRDFA_VK_TRY(vkAllocateMemory(b.device_, &mai, nullptr, &b.memory_));
  BRDFA_VK_TRY(vkBindBufferMemory(b.device_, b.buffer_, b.memory_, 0));
  if (hostVisible) BRDFA_VK_TRY(vkMapMemory(b.device_, b.memory_, 0, VK_WHOLE_SIZE, 0, &b.mapped_));
  return b;
}

TexelBuffer& TexelBuffer::operator=(TexelBuffer&& o) noexcept {
  if (this != &o) {
    reset();
    buffer_ = std::move(o.buffer_);
    view_ = std::move(o.view_);
  }
  return *this;
}

void TexelBuffer::reset() {
  view_.reset();
  buffer_.reset();
}

Result<TexelBuffer> TexelBuffer::create(VkContext& ctx, const void* data, VkDeviceSize bytes, VkFormat format) {
  TexelBuffer t;
  auto buffer = Buffer::create(ctx, bytes, VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT, true, true);
  if (!buffer) return buffer.takeError();
  t.buffer_ = std::move(buffer.value());
  std::memcpy(t.buffer_.mapped(), data, bytes);
  auto view = TexelView::create(ctx, t.buffer_, format, 0, VK_WHOLE_SIZE);
  if (!view) return view.takeError();
  t.view_ = std::move(view.value());
  return t;
}

TexelView& TexelView::operator=(TexelView&& o) noexcept {
  if (this != &o) {
    reset();
    std::swap(device_, o.device_);
    std::swap(view_, o.view_);
  }
  return *this;
}

void TexelView::reset() {
  if (device_ && view_) vkDestroyBufferView(device_, view_, nullptr);
  view_ = VK_NULL_HANDLE;
  device_ = VK_NULL_HANDLE;
}

Result<TexelView> TexelView::create(VkContext& ctx, const Buffer& buffer, VkFormat format, VkDeviceSize offset,
                                    VkDeviceSize range) {
  TexelView t;
  t.device_ = ctx.device();
  VkBufferViewCreateInfo vci{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
  vci.buffer = buffer.handle();
  vci.format = format;
  vci.offset = offset;
  vci.range = range;
  BRDFA_VK_TRY(vkCreateBufferView(t.device_, &vci, nullptr, &t.view_));
  return t;
}

Image& Image::operator=(Image&& o) noexcept {
  if (this != &o) {
    reset();
    std::swap(device_, o.device_);
    std::swap(image_, o.image_);
    std::swap(view_, o.view_);
    std::swap(memory_, o.memory_);
    std::swap(spec_, o.spec_);
  }
  return *this;
}

void Image::reset() {
  if (!device_) return;
  if (view_) vkDestroyImageView(device_, view_, nullptr);
  if (image_) vkDestroyImage(device_, image_, nullptr);
  if (memory_) vkFreeMemory(device_, memory_, nullptr);
  device_ = VK_NULL_HANDLE;
  image_ = VK_NULL_HANDLE;
  view_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
}

Result<Image> Image::create(VkContext& ctx, const ImageSpec& spec) {
  Image img;
  img.device_ = ctx.device();
  img.spec_ = spec;
  VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ici.flags = spec.cube ? VK_IMAGE_CREATE_CUBE_COMPATIBLE_BIT : 0;
  ici.imageType = VK_IMAGE_TYPE_2D;
  ici.format = spec.format;
  ici.extent = {spec.width, spec.height, 1};
  ici.mipLevels = 1;
  ici.arrayLayers = spec.layers;
  ici.samples = VK_SAMPLE_COUNT_1_BIT;
  ici.tiling = VK_IMAGE_TILING_OPTIMAL;
  ici.usage = spec.usage;
  ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  BRDFA_VK_TRY(vkCreateImage(img.device_, &ici, nullptr, &img.image_));
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(img.device_, img.image_, &req);
  auto type = ctx.findMemoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  if (!type) return type.takeError();
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = *type;
  BRDFA_VK_TRY(vkAllocateMemory(img.device_, &mai, nullptr, &img.memory_));
  BRDFA_VK_TRY(vkBindImageMemory(img.device_, img.image_, img.memory_, 0));

  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = img.image_;
  vci.viewType = spec.cube ? VK_IMAGE_VIEW_TYPE_CUBE : VK_IMAGE_VIEW_TYPE_2D;
  vci.format = spec.format;
  vci.subresourceRange = {spec.aspect, 0, 1, 0, spec.layers};
  BRDFA_VK_TRY(vkCreateImageView(img.device_, &vci, nullptr, &img.view_));
  return img;
}

CommandContext& CommandContext::operator=(CommandContext&& o) noexcept {
  if (this != &o) {
    reset();
    std::swap(ctx_, o.ctx_);
    std::swap(pool_, o.pool_);
    std::swap(commands_, o.commands_);
    std::swap(fence_, o.fence_);
  }
  return *this;
}

void CommandContext::reset() {
  if (!ctx_) return;
  if (fence_) vkDestroyFence(ctx_->device(), fence_, nullptr);
  if (pool_) vkDestroyCommandPool(ctx_->device(), pool_, nullptr);
  ctx_ = nullptr;
  pool_ = VK_NULL_HANDLE;
  commands_ = VK_NULL_HANDLE;
  fence_ = VK_NULL_HANDLE;
}

Result<CommandContext> CommandContext::create(VkContext& ctx) {
  CommandContext c;
  c.ctx_ = &ctx;
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = ctx.queueFamily();
  BRDFA_VK_TRY(vkCreateCommandPool(ctx.device(), &pci, nullptr, &c.pool_));
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = c.pool_;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  BRDFA_VK_TRY(vkAllocateCommandBuffers(ctx.device(), &ai, &c.commands_));
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  BRDFA_VK_TRY(vkCreateFence(ctx.device(), &fci, nullptr, &c.fence_));
  return c;
}

Result<VkCommandBuffer> CommandContext::begin() {
  BRDFA_VK_TRY(vkResetCommandBuffer(commands_, 0));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  BRDFA_VK_TRY(vkBeginCommandBuffer(commands_, &bi));
  return commands_;
}

Result<void> CommandContext::submitAndWait(double* busyMs, bool viewPass) {
  BRDFA_VK_TRY(vkEndCommandBuffer(commands_));
  return ctx_->submitAndWait(commands_, fence_, busyMs, viewPass);
}

void memoryBarrier(VkCommandBuffer cb, VkPipelineStageFlags src, VkAccessFlags srcAccess, VkPipelineStageFlags dst,
                   VkAccessFlags dstAccess) {
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = srcAccess;
  mb.dstAccessMask = dstAccess;
  vkCmdPipelineBarrier(cb, src, dst, 0, 1, &mb, 0, nullptr, 0, nullptr);
}

void imageBarrier(VkCommandBuffer cb, const Image& image, VkImageLayout from, VkImageLayout to,
                  VkPipelineStageFlags src, VkAccessFlags srcAccess, VkPipelineStageFlags dst,
                  VkAccessFlags dstAccess) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = srcAccess;
  b.dstAccessMask = dstAccess;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image.handle();
  b.subresourceRange = {image.spec().aspect, 0, 1, 0, image.spec().layers};
  vkCmdPipelineBarrier(cb, src, dst, 0, 0, nullptr, 0, nullptr, 1, &b);
}

Result<void> uploadImage(VkContext& ctx, const Image& image, const void* texels, VkDeviceSize bytes) {
  auto staging = Buffer::create(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true);
  if (!staging) return staging.takeError();
  std::memcpy(staging->mapped(), texels, bytes);
  auto cmd = CommandContext::create(ctx);
  if (!cmd) return cmd.takeError();
  auto cb = cmd->begin();
  if (!cb) return cb.takeError();
  imageBarrier(*cb, image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
               VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, image.spec().layers};
  region.imageExtent = {image.spec().width, image.spec().height, 1};
  vkCmdCopyBufferToImage(*cb, staging->handle(), image.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
  imageBarrier(*cb, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
               VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
               VK_ACCESS_SHADER_READ_BIT);
  return cmd->submitAndWait();
}

}  // namespace brdfa
