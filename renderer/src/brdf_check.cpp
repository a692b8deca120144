// Numeric checks of a BRDF and of its sampler on the device (BrdfCheckReport and
// SamplerCheckReport in renderer.h; shaders/kernels/check*.comp.glsl).
#include <chrono>
#include <cmath>
#include <cstring>

#include "brdf_features.h"
#include "chi_square.h"
#include "renderer_impl.h"
#include "vk_check.h"

namespace brdfa {

namespace {

constexpr uint32_t kViews = 40;  // BRDFA_VIEWS in check.comp.glsl
// check_sampler.comp.glsl: 4 views x 32 chunks of 2048 samples, 128 cells + 2 summary vec4 +
// the chi-square histogram of 10 x 20 cells (four counts to a vec4) per chunk; then, with
// pdfBRDF, one invocation per 4 chi-square cells and view computing their probabilities.
constexpr uint32_t kSamplerViews = 4, kSamplerChunks = 32, kChunkSamples = 2048, kCells = 128;
constexpr int kSamplerViewDeg[kSamplerViews] = {0, 30, 60, 80};  // BRDFA_VIEW_DEG
constexpr uint32_t kChi2Cells = 10 * 20, kChi2Vec4s = kChi2Cells / 4;
constexpr uint32_t kSamplerStride = kCells + 2 + kChi2Vec4s;
constexpr uint32_t kSamplingInvocations = kSamplerViews * kSamplerChunks;
constexpr uint32_t kExpectedInvocations = kSamplerViews * kChi2Vec4s;
constexpr double kChi2Significance = 0.01;  // pbrt-v4's CHI2_SLEVEL, before the Sidak correction
constexpr double kChi2MinExpected = 5.0;    // pbrt-v4's CHI2_MINFREQ: smaller cells are pooled

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

struct PoolOwner {
  VkDevice device = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  ~PoolOwner() {
    if (pool) vkDestroyDescriptorPool(device, pool, nullptr);
  }
};

// z-score of a mean estimated from n samples with the given sums against `expected`.
double zScore(double sum, double sumSq, double n, double expected) {
  double mean = sum / n;
  double var = std::max(sumSq / n - mean * mean, 0.0) / std::max(n - 1.0, 1.0);
  double diff = mean - expected;
  if (var <= 0) return diff == 0 ? 0 : INFINITY;
  return std::fabs(diff) / std::sqrt(var);
}

}  // namespace

Result<void> RendererImpl::runCheckKernel(const BrdfDefinition& brdf, const char* kernelName, uint32_t invocations,
                                          uint32_t outputVec4s,
                                          const std::vector<std::map<std::string, Vec3>>& settings,
                                          const std::function<void(const float*)>& consume) {
  if (brdf.format == BrdfFormat::Legacy)
    return makeError(ErrorCode::Unsupported, "legacy render() BRDFs are rendered, not analysed");
  auto kernel = compiledKernel(assembleCheckProgram(brdf, kernelName));
  if (!kernel) return kernel.takeError();
  const ParamBlockLayout& layout = (*kernel)->params;
  VkContext& ctx = *ctx_;
  auto output = Buffer::create(ctx, VkDeviceSize(outputVec4s) * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
  if (!output) return output.takeError();
  auto params = Buffer::create(ctx, layout.size, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true);
  if (!params) return params.takeError();
  auto cmd = CommandContext::create(ctx);
  if (!cmd) return cmd.takeError();
  auto furnace = environment("furnace");
  if (!furnace) return furnace.takeError();

  // Set 0 carries the output in the accumulator binding (3); set 1 the parameter block.
  PoolOwner res;
  res.device = ctx.device();
  VkDescriptorPoolSize sizes[3] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 7},
                                   {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 5},
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
  // buffers, the furnace for the environment, the parameters for the unused transform, white
  // for the textures.
  VkDescriptorBufferInfo outInfo{output->handle(), 0, VK_WHOLE_SIZE};
  VkDescriptorBufferInfo paramInfo{params->handle(), 0, VK_WHOLE_SIZE};
  VkDescriptorImageInfo envInfo{envSampler_, (*furnace)->cube.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  std::vector<VkWriteDescriptorSet> writes;
  for (uint32_t binding : {0u, 3u, 4u, 6u, 7u, 8u, 9u})
    writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[0], binding, 0, 1,
                      VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, nullptr, &outInfo, nullptr});
  writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[0], 5, 0, 1,
                    VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, &envInfo, nullptr, nullptr});
  for (uint32_t binding : {0u, 1u})
    writes.push_back({VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, sets[1], binding, 0, 1,
                      VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, nullptr, &paramInfo, nullptr});
  vkUpdateDescriptorSets(ctx.device(), static_cast<uint32_t>(writes.size()), writes.data(), 0, nullptr);
  writeDefaultTextures(sets[1]);  // textures read as white, the neutral value of DESIGN.md

  for (const auto& setting : settings) {
    std::vector<uint8_t> packed = layout.pack(brdf, setting);
    std::memcpy(params->mapped(), packed.data(), packed.size());
    auto cb = cmd->begin();
    if (!cb) return cb.takeError();
    vkCmdBindPipeline(*cb, VK_PIPELINE_BIND_POINT_COMPUTE, (*kernel)->kernel->pipeline());
    vkCmdBindDescriptorSets(*cb, VK_PIPELINE_BIND_POINT_COMPUTE, computeLayout_, 0, 2, sets, 0, nullptr);
    vkCmdDispatch(*cb, (invocations + 7) / 8, 1, 1);
    memoryBarrier(*cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                  VK_ACCESS_HOST_READ_BIT);
    BRDFA_TRY(cmd->submitAndWait());
    consume(static_cast<const float*>(output->mapped()));
  }
  return {};
}

Result<BrdfCheckReport> RendererImpl::checkBrdf(const BrdfDefinition& brdf) {
  const auto t0 = std::chrono::steady_clock::now();
  BrdfCheckReport report;
  auto ran = runCheckKernel(brdf, "check.comp.glsl", kViews, kViews * 2, checkSettings(brdf), [&](const float* out) {
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
  });
  if (!ran) return ran.takeError();
  report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

Result<SamplerCheckReport> RendererImpl::checkSampler(const BrdfDefinition& brdf) {
  if (!brdf.hasSampler()) return makeError(ErrorCode::InvalidArgument, "the BRDF has no '::begin sample' section");
  SamplerCheckReport report;
  // The same detection decides BRDFA_HAS_PDF in assembleCheckProgram.
  report.chi2Run = detectFeatures(brdf).samplerPdf;
  if (report.chi2Run) report.chi2Threshold = sidakSignificance(kChi2Significance, kSamplerViews);
  const uint32_t invocations = kSamplingInvocations + (report.chi2Run ? kExpectedInvocations : 0);
  const uint32_t outputVec4s = kSamplingInvocations * kSamplerStride + kExpectedInvocations;
  const double perView = double(kSamplerChunks) * kChunkSamples;
  const double cellSolidAngle = 2.0 * 3.14159265358979323846 / kCells;
  auto ran = runCheckKernel(brdf, "check_sampler.comp.glsl", invocations, outputVec4s, {{}},
                            [&](const float* out) {
    for (uint32_t view = 0; view < kSamplerViews; ++view) {
      std::vector<double> cells(3 * kCells, 0.0);
      std::vector<double> observed(kChi2Cells, 0.0);
      double albedo[4] = {0, 0, 0, 0};  // sampled sum, sum of squares; cosine sum, sum of squares
      for (uint32_t chunk = 0; chunk < kSamplerChunks; ++chunk) {
        const float* base = out + 4 * size_t((view * kSamplerChunks + chunk) * kSamplerStride);
        for (uint32_t c = 0; c < kCells; ++c)
          for (int k = 0; k < 3; ++k) cells[3 * c + k] += base[4 * c + k];
        const float* summary = base + 4 * kCells;
        report.rejected += static_cast<uint64_t>(summary[0]);
        report.maxValueMismatch = std::max(report.maxValueMismatch, double(summary[1]));
        albedo[0] += summary[2];
        albedo[1] += summary[3];
        albedo[2] += summary[4];
        albedo[3] += summary[5];
        report.maxPdfMismatch = std::max(report.maxPdfMismatch, double(summary[6]));
        const float* histogram = summary + 8;
        for (uint32_t c = 0; c < kChi2Cells; ++c) observed[c] += histogram[c];
      }
      report.samples += static_cast<uint64_t>(perView);
      for (uint32_t c = 0; c < kCells; ++c) {
        if (cells[3 * c] < 100) continue;  // too few samples to say anything
        // Cells of the two rows next to the horizon (cos theta < 1/4) are left out: where the
        // horizon cuts a lobe (grazing views), 1/pdf is so heavy-tailed that finite-sample
        // means and their error bars are unreliable (correct samplers read 30-75% low there).
        // The albedo comparison still covers those directions.
        if (c / 16 < 2) continue;
        ++report.cellsTested;
        report.maxCellZ = std::max(report.maxCellZ, zScore(cells[3 * c + 1], cells[3 * c + 2], perView, cellSolidAngle));
      }
      // Two independent estimates of one albedo: z of their difference.
      auto meanVar = [&](double sum, double sumSq) {
        double mean = sum / perView;
        return std::pair<double, double>(mean, std::max(sumSq / perView - mean * mean, 0.0) / (perView - 1));
      };
      auto [ms, vs] = meanVar(albedo[0], albedo[1]);
      auto [mc, vc] = meanVar(albedo[2], albedo[3]);
      double sd = std::sqrt(vs + vc);
      double z = sd > 0 ? std::fabs(ms - mc) / sd : (ms == mc ? 0.0 : INFINITY);
      report.maxAlbedoZ = std::max(report.maxAlbedoZ, z);

      if (!report.chi2Run) continue;
      // Expected counts: each cell's probability under pdfBRDF times every draw of the view,
      // rejected ones included (a sampler that rejects more than its pdf says comes up short in
      // every cell). The cells cover the upper hemisphere only; the mass pdfBRDF puts below it
      // is what the rejected draws should carry, and is not a cell (see docs/api.md).
      const float* probability = out + 4 * size_t(kSamplingInvocations * kSamplerStride + view * kChi2Vec4s);
      std::vector<double> expected(kChi2Cells);
      for (uint32_t c = 0; c < kChi2Cells; ++c) expected[c] = double(probability[c]) * perView;
      ChiSquareResult chi2 = chiSquareTest(observed, expected, kChi2MinExpected);
      if (!chi2.failure.empty() && report.chi2Failure.empty())
        report.chi2Failure = "view at " + std::to_string(kSamplerViewDeg[view]) + " degrees: " + chi2.failure;
      // pValue is 0 on failure, never NaN: std::min keeps the smallest.
      report.minChi2PValue = std::min(report.minChi2PValue, chi2.pValue);
      report.chi2PValues.push_back(chi2.pValue);
    }
  });
  if (!ran) return ran.takeError();
  return report;
}

}  // namespace brdfa
