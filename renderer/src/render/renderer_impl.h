// Device-wide state shared by every RenderView: layouts, fixed pipelines, and the caches of
// compiled programs, meshes and environments.
#pragma once

#include <atomic>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <condition_variable>
#include <unordered_map>

#include "brdfa/renderer.h"

#include "assets/environment_maps.h"
#include "assets/gpu_assets.h"
#include "assets/image_decode.h"
#include "assets/meshes.h"
#include "core/memory_ledger.h"
#include "device/vk_context.h"
#include "programs/compile_pool.h"
#include "programs/compute_kernel.h"
#include "programs/glsl_compiler.h"
#include "programs/shader_sources.h"
#include "programs/spirv_disk_cache.h"
#include "programs/spirv_resources.h"

namespace brdfa {

// The G-buffer's two planes (shaders/lib/bindings.glsl): surface = object id and normal,
// detail = tangent and texCoord; bytes per pixel below.
constexpr VkFormat kGbufferSurfaceFormat = VK_FORMAT_R32G32_UINT;
constexpr VkFormat kGbufferDetailFormat = VK_FORMAT_R32G32B32A32_UINT;
constexpr VkDeviceSize kGbufferSurfaceBytes = 8, kGbufferDetailBytes = 16;
constexpr uint32_t kLeftHandedBit = 0x80000000u;  // in a surface texel's id (BRDFA_LEFT_HANDED)

// What the shade kernel runs for a BRDF, a sampling mode and an environment kind.
struct ShadeVariant {
  const char* define = "BRDFA_SAMPLING_COSINE";  // the integrator's strategy (kernels/shade.comp.glsl)
  bool useSampler = false;      // the file's sample section is compiled in
  bool misFileSampler = false;  // mis draws its BRDF side from sampleBRDF/pdfBRDF
  std::string estimator;        // FrameStats::estimator
  std::vector<std::string> warnings;
};
ShadeVariant shadeVariant(const BrdfDefinition& brdf, SamplingMode sampling, bool constantEnv);

class RendererImpl final : public Renderer, public std::enable_shared_from_this<RendererImpl> {
 public:
  static Result<std::shared_ptr<RendererImpl>> create(const RendererOptions& options);
  ~RendererImpl() override;

  const DeviceInfo& device() const override { return ctx_->info(); }
  Result<CompileInfo> compileBrdf(const BrdfDefinition& brdf) override;
  Result<std::unique_ptr<RenderView>> createView() override;
  Result<BrdfCheckReport> checkBrdf(const BrdfDefinition& brdf) override;
  Result<SamplerCheckReport> checkSampler(const BrdfDefinition& brdf) override;
  Result<EnvironmentSamplerReport> checkEnvironmentSampler(const std::string& environment) override;
  Result<std::vector<Vec3>> evaluateBrdf(const BrdfDefinition& brdf, const std::vector<ParamSetting>& settings,
                                         const std::vector<DirectionPair>& pairs) override;
  Result<std::vector<AlbedoEstimate>> estimateAlbedo(const BrdfDefinition& brdf, const std::vector<ParamSetting>& settings,
                                                     const std::vector<Vec3>& views, uint32_t samplesPerView) override;
  Result<int> preloadFromCache(const BrdfDefinition& brdf) override;
  RendererCounters counters() const override;
  // Render-target memory of views against the renderer's memory budget: replaces a view's
  // reservation of `oldBytes` by `newBytes` in one step. When that would pass the budget,
  // unused cached programs and assets are dropped first (what was dropped is in `*dropped`);
  // if it still does not fit, nothing changes and the call fails with OverBudget (its message
  // names `what` and the budget). Giving back (newBytes <= oldBytes) never fails.
  MemoryUsage memoryUsage() const { return ledger_->usage(); }
  // The resident memory this process may reach: the budget less what it reserves for the other
  // processes (the spare copy, compile workers). 0: no budget. The render worker stops the work
  // in flight past it (RendererOptions::workerMemoryBytes overrides it).
  uint64_t processMemoryLimit() const { return processMemoryLimit_; }
  Result<void> exchangeViewMemory(uint64_t oldBytes, uint64_t newBytes, const std::string& what,
                                  std::string* dropped = nullptr);
  Result<void> registerAsset(const std::string& name, AssetKind kind, const std::string& path) override;
  std::vector<std::string> environmentNames() const override;
  std::vector<std::string> meshNames() const override;
  std::vector<std::string> textureNames() const override;

  // For views.
  VkContext& ctx() { return *ctx_; }
  VkDescriptorSetLayout viewSetLayout() const { return viewSetLayout_; }
  VkDescriptorSetLayout objectSetLayout() const { return objectSetLayout_; }
  VkPipelineLayout computeLayout() const { return computeLayout_; }
  VkPipelineLayout rasterLayout() const { return rasterLayout_; }
  VkRenderPass gbufferPass() const { return gbufferPass_; }
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
  VkSampler environmentSampler() const { return envSampler_; }
  // Binds the 1x1 white texture to the four texture slots (set 1, bindings 2..5) of `objectSet`:
  // every slot of a bound set must hold a valid image (see brdf_check.cpp).
  void writeDefaultTextures(VkDescriptorSet objectSet) const;
  bool hostResolve() const { return hostResolve_; }
  bool profilePasses() const { return profilePasses_; }  // RendererOptions::profilePasses

  Result<std::shared_ptr<const GpuEnvironment>> environment(const std::string& name);
  Result<std::shared_ptr<const GpuMesh>> mesh(const std::string& name);
  Result<std::shared_ptr<const GpuTexture>> texture(const std::string& name, bool srgb);
  // Binds `textures` (null entries: white) to set 1 bindings 2..5 of `objectSet`.
  void writeTextures(VkDescriptorSet objectSet, const std::shared_ptr<const GpuTexture> (&textures)[kMaxTextures]) const;
  // The shading kernel for `brdf` in this variant, compiled once, then served from the cache
  // (`variant` is shadeVariant(brdf, sampling, constantEnv), which the caller keeps for its
  // stats); and, where `preview` is asked for (RenderSettings::previewPass) and
  // that kernel has never been dispatched on a device that compiles at the first dispatch, the
  // preview kernel (shaders/kernels/preview.comp.glsl): a small program whose preview is on
  // screen while the kernel compiles in the first pass. Its GLSL compiles on another compile
  // worker beside the kernel's. It is an optimisation: null where it does not apply (BRDFA
  // Engine files, whose render() is not a BRDF, too) or cannot be built.
  struct ShadeKernels {
    std::shared_ptr<const ShadeKernel> kernel, preview;
  };
  Result<ShadeKernels> shadeKernels(const BrdfDefinition& brdf, const ShadeVariant& variant, bool constantEnv,
                                    bool preview);
  // The device compiles a pipeline at its first dispatch (a CPU device: lavapipe's JIT), so a
  // kernel's first submission carries its compile; a GPU driver compiles at pipeline creation.
  bool compilesAtFirstDispatch() const { return ctx_->info().type == "cpu"; }

 private:
  RendererImpl() = default;
  Result<void> init(const RendererOptions& options);
  Result<void> createLayouts();
  Result<void> createGbufferPipeline();
  Result<std::unique_ptr<ComputeKernel>> createComputeKernel(const std::vector<uint32_t>& spirv);
  Result<std::unique_ptr<ComputeKernel>> compileFixedKernel(const std::vector<std::string>& defines,
                                                            const std::vector<std::string>& pieces,
                                                            const std::vector<std::string>& extensions = {});
  // GLSL -> SPIR-V through the content-addressed cache (key: hash of source + compiler). With
  // `compileOnMiss` false a program in neither cache is NotFound instead of compiled.
  Result<std::shared_ptr<const SpirvBinary>> spirv(ShaderStage stage, const std::string& source, bool* cached,
                                                   bool compileOnMiss = true);
  AssembledProgram assembleShadeProgram(const BrdfDefinition& brdf, SamplingMode sampling, bool constantEnv) const;
  // `preview`: kernels/preview.comp.glsl in place of the integrator (previewKernel).
  AssembledProgram assembleShadeProgram(const BrdfDefinition& brdf, const ShadeVariant& variant, bool constantEnv,
                                        bool preview = false) const;
  // A check kernel (kernels/<kernel>) specialized to `brdf`.
  AssembledProgram assembleCheckProgram(const BrdfDefinition& brdf, const char* kernel) const;
  // Runs a check kernel once per entry of `settings` over `invocations` invocations with an
  // output of `outputVec4s` vec4; `consume` reads the output after each run.
  Result<void> runCheckKernel(const BrdfDefinition& brdf, const char* kernel, uint32_t invocations,
                              uint32_t outputVec4s, const std::vector<std::map<std::string, Vec3>>& settings,
                              const std::function<void(const float*)>& consume,
                              const std::vector<float>& input = {}, const GpuEnvironment* env = nullptr);
  // The pipeline of an assembled program; compiled once, then served from the cache.
  // `created` (optional) tells whether this call built the pipeline.
  Result<std::shared_ptr<const ShadeKernel>> compiledKernel(const AssembledProgram& program,
                                                            bool compileOnMiss = true, bool* created = nullptr);

  std::unique_ptr<VkContext> ctx_;  // declared first: destroyed last
  std::unique_ptr<MemoryLedger> ledger_;  // outlives every reservation the caches below hold
  uint64_t processMemoryLimit_ = 0;

  // Which of the cache locks the caller of dropUnusedCaches holds (it takes the others only if
  // they are free, so it never waits and never deadlocks).
  struct HeldLocks {
    bool kernels = false, assets = false;
  };
  // MemoryLedger::Shrink: drops cached programs, SPIR-V and built-in assets that nothing but the
  // cache holds, oldest first, until `needed` bytes are given back.
  std::string dropUnusedCaches(uint64_t needed, HeldLocks held);
  MemoryLedger::Shrink shrinker(HeldLocks held) {
    return [this, held](uint64_t needed) { return dropUnusedCaches(needed, held); };
  }
  ShaderSources sources_;
  VkDescriptorSetLayout viewSetLayout_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout objectSetLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout computeLayout_ = VK_NULL_HANDLE;
  VkPipelineLayout rasterLayout_ = VK_NULL_HANDLE;
  VkRenderPass gbufferPass_ = VK_NULL_HANDLE;
  VkPipeline gbufferPipeline_ = VK_NULL_HANDLE;
  VkSampler envSampler_ = VK_NULL_HANDLE;
  VkSampler textureSampler_ = VK_NULL_HANDLE;  // iTexture0..3: linear, repeating
  Image whiteTexture_;                          // 1x1 RGBA8 (1, 1, 1, 1): an unbound texture slot
  std::unique_ptr<ComputeKernel> resolve_, backgroundConstant_, backgroundCube_;
  std::unique_ptr<ComputeKernel> previewSetupConstant_, previewSetupCube_, previewScatter_;
  bool profilePasses_ = false;
  bool hostResolve_ = false;

  std::mutex spirvMutex_;
  // Programs being compiled: a second request for one waits for it instead of compiling it too
  // (two sessions setting the same new BRDF; a view's prebuild, which compiles its programs at
  // once, and buildObjects).
  std::set<uint64_t> spirvInFlight_;
  std::condition_variable spirvDone_;
  std::unordered_map<uint64_t, std::shared_ptr<const SpirvBinary>> spirvCache_;
  std::unordered_map<uint64_t, MemoryReservation> spirvMemory_;  // what each entry above holds
  std::deque<uint64_t> spirvOrder_;  // insertion order, for a bounded cache

  std::mutex kernelMutex_;
  std::unordered_map<uint64_t, std::shared_ptr<const ShadeKernel>> kernelCache_;
  std::deque<uint64_t> kernelOrder_;

  std::atomic<uint64_t> glslCompiles_{0}, glslCompileErrors_{0}, spirvCacheHits_{0}, spirvDiskHits_{0},
      pipelinesCreated_{0};
  DurationRecorder compileTime_;
  std::unique_ptr<SpirvDiskCache> diskCache_;
  std::unique_ptr<CompilePool> compilePool_;  // every GLSL compile runs there
  std::set<DescriptorSlot> computeSlots_;      // the layout's slots a compute program may use
  // CompileError when a compiled program declares what its pipeline layout does not provide
  // (spirv_resources.h); lines point into `brdf`'s text when given.
  Result<void> checkResources(const SpirvBinary& code, const BrdfDefinition* brdf) const;

  // Asset caches. Built-ins are kept for the renderer's life; registered (uploaded) assets
  // only while a view holds them, so large uploads do not pile up in memory.
  Result<std::string> registeredPath(AssetKind kind, const std::string& name) const;  // assetMutex_ held
  // The lookup every asset kind shares (assetMutex_ held): `key` in the built-ins' cache, then in
  // the uploads' cache; else a built-in made now by `makeBuiltin()`, else the file registered as
  // (kind, name), read and `decode`d. `upload(data)` puts what was made on the device.
  template <class Gpu, class MakeBuiltin, class Decode, class Upload>
  Result<std::shared_ptr<const Gpu>> findOrLoad(AssetKind kind, const std::string& name, const std::string& key,
                                                std::map<std::string, std::shared_ptr<const Gpu>>& builtins,
                                                std::map<std::string, std::weak_ptr<const Gpu>>& uploads,
                                                MakeBuiltin makeBuiltin, Decode decode, Upload upload);
  Result<std::shared_ptr<GpuMesh>> uploadMesh(const std::string& name, const MeshData& data);
  Result<std::shared_ptr<GpuEnvironment>> uploadEnvironment(const std::string& name, const EnvironmentData& data);
  Result<std::shared_ptr<GpuTexture>> uploadTexture(const std::string& name, bool srgb, const TextureData& data);
  mutable std::mutex assetMutex_;
  std::map<std::pair<AssetKind, std::string>, std::string> registered_;  // (kind, name) -> file path
  std::map<std::string, std::shared_ptr<const GpuEnvironment>> environments_;
  std::map<std::string, std::shared_ptr<const GpuMesh>> meshes_;
  std::map<std::string, std::shared_ptr<const GpuTexture>> textures_;  // key: name + "|srgb" / "|linear"
  std::map<std::string, std::weak_ptr<const GpuEnvironment>> uploadedEnvironments_;
  std::map<std::string, std::weak_ptr<const GpuMesh>> uploadedMeshes_;
  std::map<std::string, std::weak_ptr<const GpuTexture>> uploadedTextures_;
};

}  // namespace brdfa
