// The renderer's programs: GLSL assembled from BRDF files and shaders/, compiled to SPIR-V on
// the compile workers (through an in-memory and an on-disk cache), and built into compute
// pipelines, each once, then served from the cache.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "brdfa/renderer.h"

#include "core/memory_ledger.h"
#include "device/vk_context.h"
#include "programs/compile_pool.h"
#include "programs/compute_kernel.h"
#include "programs/glsl_compiler.h"
#include "programs/program_assembler.h"
#include "programs/shader_sources.h"
#include "programs/spirv_disk_cache.h"
#include "programs/spirv_resources.h"

namespace brdfa {

// What the shade kernel runs for a BRDF, a sampling mode and an environment kind.
struct ShadeVariant {
  const char* define = "BRDFA_SAMPLING_COSINE";  // the integrator's strategy (kernels/shade.comp.glsl)
  bool useSampler = false;                       // the file's sample section is compiled in
  bool misFileSampler = false;                   // mis draws its BRDF side from sampleBRDF/pdfBRDF
  std::string estimator;                         // FrameStats::estimator
  std::vector<std::string> warnings;
};
ShadeVariant shadeVariant(const BrdfDefinition& brdf, SamplingMode sampling, bool constantEnv);

// The shaders/lib pieces of a shading program after the BRDF, in order (each may call those
// before it): the shade kernel's, and the preview kernel's fixed stages'.
const std::vector<std::string>& shadeLibPieces();

// A shading kernel and, where it applies, its preview kernel (ProgramCache::shadeKernels).
struct ShadeKernels {
  std::shared_ptr<const ShadeKernel> kernel, preview;
};

class ProgramCache {
 public:
  // `ctx`, `ledger` and `computeLayout` outlive the cache; `computeSlots` are the descriptor
  // slots the compute layout provides (what a BRDF's program may declare); `shrinker` makes
  // room in the memory budget when a pipeline does not fit.
  ProgramCache(VkContext& ctx, MemoryLedger& ledger, ShaderSources sources, std::unique_ptr<SpirvDiskCache> diskCache,
               std::unique_ptr<CompilePool> compilePool, VkPipelineLayout computeLayout,
               std::set<DescriptorSlot> computeSlots, CacheShrinker shrinker);

  const ShaderSources& sources() const { return sources_; }
  // The device compiles a pipeline at its first dispatch (a CPU device: lavapipe's JIT), so a
  // kernel's first submission carries its compile; a GPU driver compiles at pipeline creation.
  bool compilesAtFirstDispatch() const { return ctx_.info().type == "cpu"; }

  // GLSL -> SPIR-V through the content-addressed cache (key: hash of source + compiler). With
  // `compileOnMiss` false a program in neither cache is NotFound instead of compiled.
  Result<std::shared_ptr<const SpirvBinary>> spirv(ShaderStage stage, const std::string& source, bool* cached,
                                                   bool compileOnMiss = true);
  // A compute pipeline with the compute layout, built from `spirv` (not cached).
  Result<std::unique_ptr<ComputeKernel>> createComputeKernel(const std::vector<uint32_t>& spirv);
  // A fixed kernel of shaders/ (`pieces` in order, after `defines` and `extensions`).
  Result<std::unique_ptr<ComputeKernel>> compileFixedKernel(const std::vector<std::string>& defines,
                                                            const std::vector<std::string>& pieces,
                                                            const std::vector<std::string>& extensions = {});

  // Renderer::compileBrdf and Renderer::preloadFromCache (renderer.h).
  Result<CompileInfo> compileBrdf(const BrdfDefinition& brdf);
  Result<int> preloadFromCache(const BrdfDefinition& brdf);
  // The shading kernel for `brdf` in this variant, compiled once, then served from the cache
  // (`variant` is shadeVariant(brdf, sampling, constantEnv), which the caller keeps for its
  // stats); and, where `preview` is asked for (RenderSettings::previewPass) and
  // that kernel has never been dispatched on a device that compiles at the first dispatch, the
  // preview kernel (shaders/kernels/preview.comp.glsl): a small program whose preview is on
  // screen while the kernel compiles in the first pass. Its GLSL compiles on another compile
  // worker beside the kernel's. It is an optimisation: null where it does not apply (BRDFA
  // Engine files, whose render() is not a BRDF, too) or cannot be built.
  Result<ShadeKernels> shadeKernels(const BrdfDefinition& brdf, const ShadeVariant& variant, bool constantEnv,
                                    bool preview);
  // A check kernel (kernels/<kernel>) specialized to `brdf`.
  AssembledProgram assembleCheckProgram(const BrdfDefinition& brdf, const char* kernel) const;
  // The pipeline of an assembled program; compiled once, then served from the cache.
  // `created` (optional) tells whether this call built the pipeline.
  Result<std::shared_ptr<const ShadeKernel>> compiledKernel(const AssembledProgram& program, bool compileOnMiss = true,
                                                            bool* created = nullptr);

  // The compile and cache counters of RendererCounters (memory aside).
  void addCounters(RendererCounters& c) const;
  // Part of the memory budget's shrink: drops cached pipelines, then SPIR-V modules, that nothing
  // but the cache holds, oldest first, until `freed` reaches `needed`; counts them. The kernel
  // lock is taken only if free unless `kernelLockHeld`.
  void dropUnused(uint64_t needed, bool kernelLockHeld, uint64_t& freed, int& programs, int& spirvModules);

 private:
  AssembledProgram assembleShadeProgram(const BrdfDefinition& brdf, SamplingMode sampling, bool constantEnv) const;
  // `preview`: kernels/preview.comp.glsl in place of the integrator (previewKernel).
  AssembledProgram assembleShadeProgram(const BrdfDefinition& brdf, const ShadeVariant& variant, bool constantEnv,
                                        bool preview = false) const;
  // CompileError when a compiled program declares what its pipeline layout does not provide
  // (spirv_resources.h); lines point into `brdf`'s text when given.
  Result<void> checkResources(const SpirvBinary& code, const BrdfDefinition* brdf) const;

  VkContext& ctx_;
  MemoryLedger& ledger_;
  ShaderSources sources_;
  std::unique_ptr<SpirvDiskCache> diskCache_;
  std::unique_ptr<CompilePool> compilePool_;  // every GLSL compile runs there
  VkPipelineLayout computeLayout_;
  std::set<DescriptorSlot> computeSlots_;  // the layout's slots a compute program may use
  CacheShrinker shrinker_;

  std::mutex spirvMutex_;
  // Programs being compiled: a second request for one waits for it instead of compiling it too
  // (two sessions setting the same new BRDF; a view's prebuild, which compiles its programs at
  // once, and buildObjects).
  std::set<uint64_t> spirvInFlight_;
  std::condition_variable spirvDone_;
  std::unordered_map<uint64_t, std::shared_ptr<const SpirvBinary>> spirvCache_;
  std::unordered_map<uint64_t, MemoryReservation> spirvMemory_;  // what each entry above holds
  std::deque<uint64_t> spirvOrder_;                              // insertion order, for a bounded cache

  std::mutex kernelMutex_;
  std::unordered_map<uint64_t, std::shared_ptr<const ShadeKernel>> kernelCache_;
  std::deque<uint64_t> kernelOrder_;

  std::atomic<uint64_t> glslCompiles_{0}, glslCompileErrors_{0}, spirvCacheHits_{0}, spirvDiskHits_{0},
      pipelinesCreated_{0};
  DurationRecorder compileTime_;
};

}  // namespace brdfa
