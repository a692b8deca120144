#include "analysis/check_kernel.h"

#include <cstring>

#include "device/vk_check.h"

namespace brdfa::analysis {

namespace {
struct PoolOwner {
  VkDevice device = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  ~PoolOwner() {
    if (pool) vkDestroyDescriptorPool(device, pool, nullptr);
  }
};
}  // namespace

Result<void> runCheckKernel(const CheckDevice& device, const BrdfDefinition& brdf, const char* kernelName,
                            uint32_t invocations, uint32_t outputVec4s,
                            const std::vector<std::map<std::string, Vec3>>& settings,
                            const std::function<void(const float*)>& consume, const std::vector<float>& input,
                            const GpuEnvironment* env) {
  if (brdf.format == BrdfFormat::Legacy)
    return makeError(ErrorCode::Unsupported, "legacy render() BRDFs are rendered, not analysed");
  auto kernel = device.programs.compiledKernel(device.programs.assembleCheckProgram(brdf, kernelName));
  if (!kernel) return kernel.takeError();
  const ParamBlockLayout& layout = (*kernel)->params;
  VkContext& ctx = device.ctx;
  std::shared_ptr<const GpuMeasured> measured;  // a measured BRDF's table, bound at set 1 binding 6
  if (!brdf.measuredTable.empty()) {
    BRDFA_TRY_ASSIGN(measured, device.assets.measured(brdf.measuredTable));
  }
  auto output = Buffer::create(ctx, VkDeviceSize(outputVec4s) * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
  if (!output) return output.takeError();
  auto params = Buffer::create(ctx, layout.size, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true);
  if (!params) return params.takeError();
  // The kernel's input (read-only, binding 0); without one, the output stands in there.
  Buffer inputBuffer;
  if (!input.empty()) {
    auto in = Buffer::create(ctx, VkDeviceSize(input.size()) * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
    if (!in) return in.takeError();
    std::memcpy(in->mapped(), input.data(), input.size() * sizeof(float));
    inputBuffer = std::move(in.value());
  }
  auto cmd = CommandContext::create(ctx);
  if (!cmd) return cmd.takeError();
  auto furnace = device.assets.environment("furnace");
  if (!furnace) return furnace.takeError();

  // Set 0 carries the output in the accumulator binding (3); set 1 the parameter block.
  PoolOwner res;
  res.device = ctx.device();
  VkDescriptorPoolSize sizes[4] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 8},
                                   {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 5},
                                   {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 2},
                                   {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1}};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.maxSets = 2;
  pci.poolSizeCount = 4;
  pci.pPoolSizes = sizes;
  BRDFA_VK_TRY(vkCreateDescriptorPool(ctx.device(), &pci, nullptr, &res.pool));
  VkDescriptorSetLayout layouts[2] = {device.layouts.viewSet(), device.layouts.objectSet()};
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = res.pool;
  ai.descriptorSetCount = 2;
  ai.pSetLayouts = layouts;
  VkDescriptorSet sets[2];
  BRDFA_VK_TRY(vkAllocateDescriptorSets(ctx.device(), &ai, sets));
  // Every binding gets a valid resource, used or not: lavapipe reads all bindings of a bound
  // set at dispatch and crashed on unwritten ones. The output stands in for the unused storage
  // buffers, the furnace for the environment, the parameters for the unused transform, white
  // for the textures. A kernel input, when given, takes binding 0 (the G-buffer's, read-only).
  VkDescriptorBufferInfo outInfo{output->handle(), 0, VK_WHOLE_SIZE};
  VkDescriptorBufferInfo inInfo{input.empty() ? output->handle() : inputBuffer.handle(), 0, VK_WHOLE_SIZE};
  VkDescriptorBufferInfo paramInfo{params->handle(), 0, VK_WHOLE_SIZE};
  if (!env) env = furnace->get();
  VkDescriptorImageInfo envInfo{device.assets.environmentSampler(), env->cube.view(),
                                VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  const VkBufferView tableView = env->table.view();
  std::vector<VkWriteDescriptorSet> writes;
  for (uint32_t binding : {0u, 3u, 4u, 6u, 7u, 8u, 12u})
    writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[0], binding, 0, 1,
                      VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, nullptr, binding == 0 ? &inInfo : &outInfo, nullptr});
  writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[0], 9, 0, 1,
                    VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, nullptr, nullptr, &tableView});
  writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[0], 5, 0, 1,
                    VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, &envInfo, nullptr, nullptr});
  for (uint32_t binding : {0u, 1u})
    writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[1], binding, 0, 1,
                      VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, nullptr, &paramInfo, nullptr});
  vkUpdateDescriptorSets(ctx.device(), static_cast<uint32_t>(writes.size()), writes.data(), 0, nullptr);
  device.assets.writeDefaultTextures(sets[1]);  // textures read as white, the neutral value of docs/design.md
  device.assets.writeMeasured(sets[1], measured.get());

  for (const auto& setting : settings) {
    std::vector<uint8_t> packed = layout.pack(brdf, setting);
    std::memcpy(params->mapped(), packed.data(), packed.size());
    auto cb = cmd->begin();
    if (!cb) return cb.takeError();
    vkCmdBindPipeline(*cb, VK_PIPELINE_BIND_POINT_COMPUTE, (*kernel)->kernel->pipeline());
    vkCmdBindDescriptorSets(*cb, VK_PIPELINE_BIND_POINT_COMPUTE, device.layouts.compute(), 0, 2, sets, 0, nullptr);
    vkCmdDispatch(*cb, (invocations + 7) / 8, 1, 1);
    memoryBarrier(*cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                  VK_ACCESS_HOST_READ_BIT);
    BRDFA_TRY(cmd->submitAndWait());
    consume(static_cast<const float*>(output->mapped()));
  }
  return {};
}

}  // namespace brdfa::analysis
