#include "programs/pipeline_layouts.h"

#include <array>
#include <utility>

#include "device/vk_check.h"
#include "programs/compute_kernel.h"

namespace brdfa {

namespace {
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
}  // namespace

PipelineLayouts::~PipelineLayouts() {
  if (gbufferPass_) vkDestroyRenderPass(device_, gbufferPass_, nullptr);
  if (computeLayout_) vkDestroyPipelineLayout(device_, computeLayout_, nullptr);
  if (rasterLayout_) vkDestroyPipelineLayout(device_, rasterLayout_, nullptr);
  if (viewSetLayout_) vkDestroyDescriptorSetLayout(device_, viewSetLayout_, nullptr);
  if (objectSetLayout_) vkDestroyDescriptorSetLayout(device_, objectSetLayout_, nullptr);
}

Result<void> PipelineLayouts::create() {
  VkDevice d = device_;
  // Set 0: one view's G-buffer, accumulators, counters, environment and outputs
  // (bindings as in shaders/lib/bindings.glsl).
  const std::array<std::pair<uint32_t, VkDescriptorType>, 12> viewBindings = {
      {{0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
       {3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
       {4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
       {5, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
       {6, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
       {7, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
       {8, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
       {9, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER},
       {10, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER},
       {11, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER},
       {12, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
       {13, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER}}};
  std::array<VkDescriptorSetLayoutBinding, viewBindings.size()> view{};
  for (size_t i = 0; i < view.size(); ++i)
    view[i] = {viewBindings[i].first, viewBindings[i].second, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo li{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  li.bindingCount = static_cast<uint32_t>(view.size());
  li.pBindings = view.data();
  BRDFA_VK_TRY(vkCreateDescriptorSetLayout(d, &li, nullptr, &viewSetLayout_));

  // Set 1: one object's BRDF parameters (shading), transform (raster), textures
  // iTexture0..3 (shading; lib/brdf_inputs.glsl) and measured table (shading;
  // lib/terms/measured_merl.glsl).
  std::array<VkDescriptorSetLayoutBinding, 7> object{};
  object[0] = {0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  object[1] = {1, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
               nullptr};
  for (uint32_t t = 0; t < 4; ++t)
    object[2 + t] = {2 + t, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  object[6] = {6, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  li.bindingCount = static_cast<uint32_t>(object.size());
  li.pBindings = object.data();
  // The slots a compute program may declare: what a BRDF's text adds beyond them is refused.
  for (const auto& [binding, type] : viewBindings) computeSlots_.insert({0, binding});
  for (const VkDescriptorSetLayoutBinding& b : object)
    if (b.stageFlags & VK_SHADER_STAGE_COMPUTE_BIT) computeSlots_.insert({1, b.binding});
  BRDFA_VK_TRY(vkCreateDescriptorSetLayout(d, &li, nullptr, &objectSetLayout_));

  VkDescriptorSetLayout sets[2] = {viewSetLayout_, objectSetLayout_};
  VkPushConstantRange computePush{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(ComputePush)};
  VkPipelineLayoutCreateInfo pli{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pli.setLayoutCount = 2;
  pli.pSetLayouts = sets;
  pli.pushConstantRangeCount = 1;
  pli.pPushConstantRanges = &computePush;
  BRDFA_VK_TRY(vkCreatePipelineLayout(d, &pli, nullptr, &computeLayout_));

  VkPushConstantRange rasterPush{VK_SHADER_STAGE_VERTEX_BIT, 0, 64};  // mat4 viewProj
  pli.pPushConstantRanges = &rasterPush;
  BRDFA_VK_TRY(vkCreatePipelineLayout(d, &pli, nullptr, &rasterLayout_));

  // G-buffer render pass: the surface and detail targets (lib/bindings.glsl) + depth; the
  // targets end ready to be copied into the G-buffer buffer the kernels read.
  std::array<VkAttachmentDescription, 3> att{};
  for (int i = 0; i < 3; ++i) {
    const bool color = i < 2;
    att[i].format = i == 0 ? kGbufferSurfaceFormat : i == 1 ? kGbufferDetailFormat : kDepthFormat;
    att[i].samples = VK_SAMPLE_COUNT_1_BIT;
    att[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    att[i].storeOp = color ? VK_ATTACHMENT_STORE_OP_STORE : VK_ATTACHMENT_STORE_OP_DONT_CARE;
    att[i].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    att[i].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    att[i].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    att[i].finalLayout =
        color ? VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL : VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  }
  VkAttachmentReference colors[2] = {{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
                                     {1, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL}};
  VkAttachmentReference depth{2, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  VkSubpassDescription sub{};
  sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  sub.colorAttachmentCount = 2;
  sub.pColorAttachments = colors;
  sub.pDepthStencilAttachment = &depth;
  std::array<VkSubpassDependency, 2> deps{};
  // Earlier copies out of the targets finish before they are cleared and rewritten.
  deps[0] = {VK_SUBPASS_EXTERNAL,
             0,
             VK_PIPELINE_STAGE_TRANSFER_BIT,
             VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT,
             0,
             VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
             0};
  // The written targets are visible to the copy into the G-buffer storage buffer.
  deps[1] = {0,
             VK_SUBPASS_EXTERNAL,
             VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
             VK_PIPELINE_STAGE_TRANSFER_BIT,
             VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
             VK_ACCESS_TRANSFER_READ_BIT,
             0};
  VkRenderPassCreateInfo rpi{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  rpi.attachmentCount = static_cast<uint32_t>(att.size());
  rpi.pAttachments = att.data();
  rpi.subpassCount = 1;
  rpi.pSubpasses = &sub;
  rpi.dependencyCount = static_cast<uint32_t>(deps.size());
  rpi.pDependencies = deps.data();
  BRDFA_VK_TRY(vkCreateRenderPass(d, &rpi, nullptr, &gbufferPass_));
  return {};
}

}  // namespace brdfa
