// Numeric checks of a BRDF on the device (see BrdfCheckReport in renderer.h and
// shaders/kernels/check.comp.glsl).
#include <chrono>
#include <cmath>
#include <cstring>

#include "renderer_impl.h"
#include "vk_check.h"

namespace brdfa {

namespace {

constexpr uint32_t kViews = 40;  // BRDFA_VIEWS in check.comp.glsl

// The parameter settings checked: all defaults, then each parameter alone at its minimum and
// its maximum (colors at black and white, bools at false and true).
std::vector<std::map<std::string, Vec3>> checkSettings(const BrdfDefinition& brdf) {
  std::vector<std::map<std::string, Vec3>> settings(1);
  for (const BrdfParam& p : brdf.params) {
    Vec3 lo{p.min, p.min, p.min}, hi{p.max, p.max, p.max};
    if (p.type == ParamType::Color) lo = {0, 0, 0}, hi = {1, 1, 1};
    if (p.type == ParamType::Bool) lo = {0, 0, 0}, hi = {1, 0, 0};
    settings.push_back({{p.name, lo}});
    settings.push_back({{p.name, hi}});
  }
  return settings;
}

// Plain Vulkan objects of one check, released however the check ends.
struct CheckResources {
  VkDevice device = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  ~CheckResources() {
    if (pool) vkDestroyDescriptorPool(device, pool, nullptr);
  }
};

}  // namespace

Result<BrdfCheckReport> RendererImpl::checkBrdf(const BrdfDefinition& brdf) {
  const auto t0 = std::chrono::steady_clock::now();
  if (brdf.format == BrdfFormat::Legacy)
    return makeError(ErrorCode::Unsupported, "legacy render() BRDFs are rendered, not analysed");
  auto kernel = compiledKernel(assembleCheckProgram(brdf));
  if (!kernel) return kernel.takeError();
  const ParamBlockLayout& layout = (*kernel)->params;

  VkContext& ctx = *ctx_;
  auto output = Buffer::create(ctx, kViews * 2 * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
  if (!output) return output.takeError();
  auto params = Buffer::create(ctx, layout.size, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true);
  if (!params) return params.takeError();
  auto cmd = CommandContext::create(ctx);
  if (!cmd) return cmd.takeError();

  // Set 0 carries the output in the accumulator binding (3); set 1 the parameter block.
  CheckResources res;
  res.device = ctx.device();
  VkDescriptorPoolSize sizes[3] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 6},
                                   {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1},
                                   {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 2}};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.maxSets = 2;
  pci.poolSizeCount = 3;
  pci.pPoolSizes = sizes;
  BRDFA_VK_TRY(vkCreateDescriptorPool(ctx.device(), &pci, nullptr, &res.pool));
  VkDescriptorSetLayout layouts[2] = {viewSetLayout_, objectSetLayout_};
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = res.pool;
  ai.descriptorSetCount = 2;
  ai.pSetLayouts = layouts;
  VkDescriptorSet sets[2];
  BRDFA_VK_TRY(vkAllocateDescriptorSets(ctx.device(), &ai, sets));
  // Every binding gets a valid resource, used or not: lavapipe reads all bindings of a bound
  // set at dispatch and crashed on unwritten ones. The output stands in for the unused storage
  // buffers, the furnace for the environment, the parameters for the unused transform.
  auto furnace = environment("furnace");
  if (!furnace) return furnace.takeError();
  VkDescriptorBufferInfo outInfo{output->handle(), 0, VK_WHOLE_SIZE};
  VkDescriptorBufferInfo paramInfo{params->handle(), 0, VK_WHOLE_SIZE};
  VkDescriptorImageInfo envInfo{envSampler_, (*furnace)->cube.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  std::vector<VkWriteDescriptorSet> writes;
  for (uint32_t binding : {0u, 3u, 4u, 6u, 7u, 8u})
    writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[0], binding, 0, 1,
                      VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, nullptr, &outInfo, nullptr});
  writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[0], 5, 0, 1,
                    VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, &envInfo, nullptr, nullptr});
  for (uint32_t binding : {0u, 1u})
    writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[1], binding, 0, 1,
                      VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, nullptr, &paramInfo, nullptr});
  vkUpdateDescriptorSets(ctx.device(), static_cast<uint32_t>(writes.size()), writes.data(), 0, nullptr);

  BrdfCheckReport report;
  for (const auto& setting : checkSettings(brdf)) {
    std::vector<uint8_t> packed = layout.pack(brdf, setting);
    std::memcpy(params->mapped(), packed.data(), packed.size());
    auto cb = cmd->begin();
    if (!cb) return cb.takeError();
    vkCmdBindPipeline(*cb, VK_PIPELINE_BIND_POINT_COMPUTE, (*kernel)->kernel->pipeline());
    vkCmdBindDescriptorSets(*cb, VK_PIPELINE_BIND_POINT_COMPUTE, computeLayout_, 0, 2, sets, 0, nullptr);
    vkCmdDispatch(*cb, (kViews + 7) / 8, 1, 1);
    memoryBarrier(*cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                  VK_ACCESS_HOST_READ_BIT);
    BRDFA_TRY(cmd->submitAndWait());
    const auto* out = static_cast<const float*>(output->mapped());
    for (uint32_t v = 0; v < kViews; ++v) {
      const float* counts = out + 8 * v;
      const float* albedo = counts + 4;
      report.nanCount += static_cast<uint64_t>(counts[0]);
      report.infCount += static_cast<uint64_t>(counts[1]);
      report.negativeCount += static_cast<uint64_t>(counts[2]);
      report.evaluations += static_cast<uint64_t>(counts[3]);
      if (std::isfinite(albedo[0])) report.maxAlbedo = std::max(report.maxAlbedo, double(albedo[0]));
      // Only a significant excess counts: a near-delta lobe gives a wild estimate with a
      // standard error to match.
      if (albedo[0] - 3.0 * albedo[1] > 1.01) ++report.albedoAboveOne;
      report.maxReciprocityError = std::max(report.maxReciprocityError, double(albedo[2]));
    }
  }
  report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace brdfa
