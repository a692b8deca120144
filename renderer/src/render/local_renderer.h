// Device-wide state shared by every RenderView: the device, the memory budget, the program and
// asset caches, and the views' fixed pipelines. It composes those parts and implements the
// public Renderer interface on them.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "brdfa/renderer.h"

#include "analysis/check_kernel.h"
#include "assets/asset_cache.h"
#include "assets/gpu_assets.h"
#include "core/memory_ledger.h"
#include "device/vk_context.h"
#include "programs/compute_kernel.h"
#include "programs/pipeline_layouts.h"
#include "programs/program_cache.h"

namespace brdfa {

constexpr uint32_t kLeftHandedBit = 0x80000000u;  // in a surface texel's id (BRDFA_LEFT_HANDED)

class LocalRenderer final : public Renderer, public std::enable_shared_from_this<LocalRenderer> {
 public:
  static Result<std::shared_ptr<LocalRenderer>> create(const RendererOptions& options);
  ~LocalRenderer() override;

  const DeviceInfo& device() const override { return ctx_->info(); }
  Result<CompileInfo> compileBrdf(const BrdfDefinition& brdf) override { return programs_->compileBrdf(brdf); }
  Result<std::unique_ptr<RenderView>> createView() override;
  Result<BrdfCheckReport> checkBrdf(const BrdfDefinition& brdf) override;
  Result<SamplerCheckReport> checkSampler(const BrdfDefinition& brdf) override;
  Result<EnvironmentSamplerReport> checkEnvironmentSampler(const std::string& environment) override;
  Result<std::vector<Vec3>> evaluateBrdf(const BrdfDefinition& brdf, const std::vector<ParamSetting>& settings,
                                         const std::vector<DirectionPair>& pairs) override;
  Result<std::vector<AlbedoEstimate>> estimateAlbedo(const BrdfDefinition& brdf,
                                                     const std::vector<ParamSetting>& settings,
                                                     const std::vector<Vec3>& views, uint32_t samplesPerView) override;
  Result<int> preloadFromCache(const BrdfDefinition& brdf) override { return programs_->preloadFromCache(brdf); }
  RendererCounters counters() const override;
  MemoryUsage memoryUsage() const { return ledger_->usage(); }
  // The resident memory this process may reach: the budget less what it reserves for the other
  // processes (the spare copy, compile workers). 0: no budget. The render worker stops the work
  // in flight past it (RendererOptions::workerMemoryBytes overrides it).
  uint64_t processMemoryLimit() const { return processMemoryLimit_; }
  // Render-target memory of views against the renderer's memory budget: replaces a view's
  // reservation of `oldBytes` by `newBytes` in one step. When that would pass the budget,
  // unused cached programs and assets are dropped first (what was dropped is in `*dropped`);
  // if it still does not fit, nothing changes and the call fails with OverBudget (its message
  // names `what` and the budget). Giving back (newBytes <= oldBytes) never fails.
  Result<void> exchangeViewMemory(uint64_t oldBytes, uint64_t newBytes, const std::string& what,
                                  std::string* dropped = nullptr);
  Result<void> registerAsset(const std::string& name, AssetKind kind, const std::string& path) override {
    return assets_->registerAsset(name, kind, path);
  }
  std::vector<std::string> environmentNames() const override { return assets_->environmentNames(); }
  std::vector<std::string> meshNames() const override { return assets_->meshNames(); }
  std::vector<std::string> textureNames() const override { return assets_->textureNames(); }

  // For views.
  VkContext& ctx() { return *ctx_; }
  VkDescriptorSetLayout viewSetLayout() const { return layouts_->viewSet(); }
  VkDescriptorSetLayout objectSetLayout() const { return layouts_->objectSet(); }
  VkPipelineLayout computeLayout() const { return layouts_->compute(); }
  VkPipelineLayout rasterLayout() const { return layouts_->raster(); }
  VkRenderPass gbufferPass() const { return layouts_->gbufferPass(); }
  VkPipeline gbufferPipeline() const { return gbufferPipeline_; }
  VkPipeline resolvePipeline() const { return resolve_->pipeline(); }
  VkPipeline backgroundPipeline(bool constantEnv) const {
    return (constantEnv ? backgroundConstant_ : backgroundCube_)->pipeline();
  }
  // The preview kernel's fixed first and last stages (kernels/preview_setup.comp.glsl,
  // kernels/preview_scatter.comp.glsl), around a program's preview stage (shadeKernels).
  VkPipeline previewSetupPipeline(bool constantEnv) const {
    return (constantEnv ? previewSetupConstant_ : previewSetupCube_)->pipeline();
  }
  VkPipeline previewScatterPipeline() const { return previewScatter_->pipeline(); }
  VkSampler environmentSampler() const { return assets_->environmentSampler(); }
  // AssetCache::writeDefaultTextures and writeTextures.
  void writeDefaultTextures(VkDescriptorSet objectSet) const { assets_->writeDefaultTextures(objectSet); }
  void writeTextures(VkDescriptorSet objectSet,
                     const std::shared_ptr<const GpuTexture> (&textures)[kMaxTextures]) const {
    assets_->writeTextures(objectSet, textures);
  }
  void writeMeasured(VkDescriptorSet objectSet, const GpuMeasured* table) const {
    assets_->writeMeasured(objectSet, table);
  }
  Result<std::shared_ptr<const GpuMeasured>> measured(const std::string& name) { return assets_->measured(name); }
  bool hostResolve() const { return hostResolve_; }
  bool profilePasses() const { return profilePasses_; }  // RendererOptions::profilePasses

  Result<std::shared_ptr<const GpuEnvironment>> environment(const std::string& name) {
    return assets_->environment(name);
  }
  Result<std::shared_ptr<const GpuMesh>> mesh(const std::string& name) { return assets_->mesh(name); }
  Result<std::shared_ptr<const GpuTexture>> texture(const std::string& name, bool srgb) {
    return assets_->texture(name, srgb);
  }
  // ProgramCache::shadeKernels.
  using ShadeKernels = brdfa::ShadeKernels;
  Result<ShadeKernels> shadeKernels(const BrdfDefinition& brdf, const ShadeVariant& variant, bool constantEnv,
                                    bool preview) {
    return programs_->shadeKernels(brdf, variant, constantEnv, preview);
  }
  // The device compiles a pipeline at its first dispatch (ProgramCache::compilesAtFirstDispatch).
  bool compilesAtFirstDispatch() const { return ctx_->info().type == "cpu"; }

 private:
  LocalRenderer() = default;
  Result<void> init(const RendererOptions& options);
  Result<void> createFixedKernels();
  Result<void> createGbufferPipeline();
  // What the process and its helpers hold before any session, against the memory budget.
  void reserveFixedMemory(const RendererOptions& options, size_t compileWorkers);
  analysis::CheckDevice checkDevice() { return {*ctx_, *layouts_, *programs_, *assets_}; }

  // MemoryLedger::Shrink: drops cached programs, SPIR-V and built-in assets that nothing but the
  // cache holds, oldest first, until `needed` bytes are given back.
  std::string dropUnusedCaches(uint64_t needed, HeldCacheLocks held);
  MemoryLedger::Shrink shrinker(HeldCacheLocks held) {
    return [this, held](uint64_t needed) { return dropUnusedCaches(needed, held); };
  }

  std::unique_ptr<VkContext> ctx_;        // declared first: destroyed last
  std::unique_ptr<MemoryLedger> ledger_;  // outlives every reservation the caches below hold
  uint64_t processMemoryLimit_ = 0;
  std::unique_ptr<PipelineLayouts> layouts_;
  std::unique_ptr<ProgramCache> programs_;
  std::unique_ptr<AssetCache> assets_;
  VkPipeline gbufferPipeline_ = VK_NULL_HANDLE;
  std::unique_ptr<ComputeKernel> resolve_, backgroundConstant_, backgroundCube_;
  std::unique_ptr<ComputeKernel> previewSetupConstant_, previewSetupCube_, previewScatter_;
  bool profilePasses_ = false;
  bool hostResolve_ = false;
};

}  // namespace brdfa
