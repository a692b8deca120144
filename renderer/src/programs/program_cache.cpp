#include "programs/program_cache.h"

#include <cctype>
#include <chrono>
#include <future>
#include <optional>

#include "device/device_activity.h"
#include "device/vk_check.h"
#include "programs/brdf_features.h"

namespace brdfa {

namespace {
constexpr size_t kMaxCachedPrograms = 256;
// What one built shading pipeline is counted at against the memory budget: the worker's
// resident memory grows by about this much a pipeline on lavapipe (LLVM's machine code and its
// bookkeeping); a GPU driver keeps less on the host.
constexpr uint64_t kPipelineBytesEstimate = 4ull << 20;

template <class Map>
void evictOldest(Map& map, std::deque<uint64_t>& order) {
  while (order.size() > kMaxCachedPrograms) {
    map.erase(order.front());
    order.pop_front();
  }
}

// Erases entries of `cache` (oldest first, in `order`) that nothing but the cache holds, until
// `freed` reaches `needed`; counts them in `count`.
template <class Map>
void dropUnusedEntries(Map& cache, std::deque<uint64_t>& order, uint64_t needed, uint64_t& freed, int& count,
                       const std::function<uint64_t(uint64_t)>& bytesOf) {
  for (auto it = order.begin(); it != order.end() && freed < needed;) {
    auto entry = cache.find(*it);
    if (entry != cache.end() && entry->second.use_count() == 1) {
      freed += bytesOf(*it);
      ++count;
      cache.erase(entry);
      it = order.erase(it);
    } else {
      ++it;
    }
  }
}
}  // namespace

const std::vector<std::string>& shadeLibPieces() {
  static const std::vector<std::string> pieces = {"lib/bindings.glsl",
                                                  "lib/gbuffer_encoding.glsl",
                                                  "lib/random.glsl",
                                                  "lib/frame.glsl",
                                                  "lib/sampling.glsl",
                                                  "lib/environment.glsl",
                                                  "lib/environment_sampling.glsl",
                                                  "lib/shade_pixel.glsl"};
  return pieces;
}

ProgramCache::ProgramCache(VkContext& ctx, MemoryLedger& ledger, ShaderSources sources,
                           std::unique_ptr<SpirvDiskCache> diskCache, std::unique_ptr<CompilePool> compilePool,
                           VkPipelineLayout computeLayout, std::set<DescriptorSlot> computeSlots,
                           CacheShrinker shrinker)
    : ctx_(ctx),
      ledger_(ledger),
      sources_(std::move(sources)),
      diskCache_(std::move(diskCache)),
      compilePool_(std::move(compilePool)),
      computeLayout_(computeLayout),
      computeSlots_(std::move(computeSlots)),
      shrinker_(std::move(shrinker)) {}

Result<std::unique_ptr<ComputeKernel>> ProgramCache::createComputeKernel(const std::vector<uint32_t>& code) {
  VkDevice d = ctx_.device();
  VkShaderModuleCreateInfo mci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  mci.codeSize = code.size() * 4;
  mci.pCode = code.data();
  VkShaderModule module;
  BRDFA_VK_TRY(vkCreateShaderModule(d, &mci, nullptr, &module));
  VkComputePipelineCreateInfo cpi{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  cpi.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  cpi.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  cpi.stage.module = module;
  cpi.stage.pName = "main";
  cpi.layout = computeLayout_;
  VkPipeline pipeline;
  VkResult r;
  {
    // The driver compiles the program here (lavapipe: LLVM), for as long as the program makes it.
    device_activity::Scope building(device_activity::Kind::PipelineBuild);
    r = vkCreateComputePipelines(d, VK_NULL_HANDLE, 1, &cpi, nullptr, &pipeline);
  }
  vkDestroyShaderModule(d, module, nullptr);
  if (r != VK_SUCCESS) return vkError(r, "vkCreateComputePipelines");
  return std::make_unique<ComputeKernel>(d, pipeline);
}

Result<std::unique_ptr<ComputeKernel>> ProgramCache::compileFixedKernel(const std::vector<std::string>& defines,
                                                                        const std::vector<std::string>& pieces,
                                                                        const std::vector<std::string>& extensions) {
  for (const auto& p : pieces)
    if (sources_.get(p).empty()) return makeError(ErrorCode::NotFound, "shader source missing: " + p);
  auto code = spirv(ShaderStage::Compute, sources_.assembleFixed(defines, pieces, extensions), nullptr);
  if (!code) return code.takeError();
  return createComputeKernel((*code)->words);
}

Result<std::shared_ptr<const SpirvBinary>> ProgramCache::spirv(ShaderStage stage, const std::string& source,
                                                               bool* cached, bool compileOnMiss) {
  static const std::string compiler = compilerVersion();
  uint64_t key = fnv1a64(source, fnv1a64(compiler) ^ static_cast<uint64_t>(stage));
  {
    std::unique_lock<std::mutex> lock(spirvMutex_);
    spirvDone_.wait(lock, [&] { return !spirvInFlight_.count(key); });
    auto it = spirvCache_.find(key);
    if (it != spirvCache_.end()) {
      if (cached) *cached = true;
      ++spirvCacheHits_;
      return it->second;
    }
    spirvInFlight_.insert(key);
  }
  struct InFlight {
    ProgramCache* r;
    uint64_t key;
    ~InFlight() {
      {
        std::lock_guard<std::mutex> lock(r->spirvMutex_);
        r->spirvInFlight_.erase(key);
      }
      r->spirvDone_.notify_all();
    }
  } inFlight{this, key};
  std::shared_ptr<const SpirvBinary> shared;
  if (auto words = diskCache_->load(key, source.size())) {
    ++spirvDiskHits_;
    auto binary = std::make_shared<SpirvBinary>();
    binary->words = std::move(*words);
    shared = binary;
  } else if (!compileOnMiss) {
    return makeError(ErrorCode::NotFound, "program not in the SPIR-V cache");
  } else {
    ++glslCompiles_;
    const auto start = std::chrono::steady_clock::now();
    auto compiled = compilePool_->compile(stage, source);
    compileTime_.add(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (!compiled) {
      ++glslCompileErrors_;
      return compiled.takeError();
    }
    diskCache_->store(key, source.size(), compiled->words);
    shared = std::make_shared<const SpirvBinary>(std::move(compiled.value()));
  }
  if (cached) *cached = false;
  // Keeping it in memory is optional: when the budget has no room, it is served from disk.
  const uint64_t bytes = shared->words.size() * sizeof(uint32_t);
  if (!ledger_.reserve(MemoryUse::Programs, bytes, "a SPIR-V cache entry")) return shared;
  MemoryReservation held(&ledger_, MemoryUse::Programs, bytes);
  std::lock_guard<std::mutex> lock(spirvMutex_);
  if (!spirvCache_.emplace(key, shared).second) return shared;  // another thread cached it first
  spirvMemory_[key] = std::move(held);
  spirvOrder_.push_back(key);
  while (spirvOrder_.size() > kMaxCachedPrograms) {
    spirvCache_.erase(spirvOrder_.front());
    spirvMemory_.erase(spirvOrder_.front());
    spirvOrder_.pop_front();
  }
  return shared;
}

ShadeVariant shadeVariant(const BrdfDefinition& brdf, SamplingMode sampling, bool constantEnv) {
  ShadeVariant v;
  if (brdf.format == BrdfFormat::Legacy) {
    // A legacy render() file always runs the engine's uniform average (kernels/shade.comp.glsl).
    v.define = "BRDFA_LEGACY_RENDER";
    v.estimator = "legacy";
    if (sampling != SamplingMode::Uniform)
      v.warnings.push_back("a legacy render() file runs the BRDFA Engine's estimator, whatever the sampling mode");
    return v;
  }
  const bool sampler = brdf.hasSampler();
  const bool pdf = sampler && detectFeatures(brdf).samplerPdf;
  // The BRDF side on its own: the file's sampler, else cosine.
  auto brdfSide = [&](bool forMis) {
    if (sampler) {
      v.define = "BRDFA_SAMPLING_BRDF";
      v.useSampler = true;
      v.estimator = "brdf";
    } else {
      v.define = "BRDFA_SAMPLING_COSINE";
      v.estimator = "cosine";
      if (!forMis) v.warnings.push_back("the BRDF has no ::begin sample section: brdf sampling falls back to cosine");
    }
  };
  switch (sampling) {
    case SamplingMode::Cosine:
      v.define = "BRDFA_SAMPLING_COSINE";
      v.estimator = "cosine";
      break;
    case SamplingMode::Uniform:
      v.define = "BRDFA_SAMPLING_UNIFORM";
      v.estimator = "uniform";
      break;
    case SamplingMode::Brdf: brdfSide(false); break;
    case SamplingMode::Environment:
      v.define = "BRDFA_SAMPLING_ENVIRONMENT";
      v.estimator = "environment";
      break;
    case SamplingMode::Mis:
      if (constantEnv) {
        // A constant environment adds no shape to the integrand: the BRDF side alone is the
        // better estimator (and exact for a Lambertian with cosine sampling).
        brdfSide(true);
        break;
      }
      v.define = "BRDFA_SAMPLING_MIS";
      v.useSampler = pdf;
      v.misFileSampler = pdf;
      v.estimator = pdf ? "mis(environment+brdf)" : "mis(environment+cosine)";
      if (sampler && !pdf)
        v.warnings.push_back(
            "sampleBRDF without pdfBRDF cannot take part in MIS: mis combines the environment "
            "with cosine sampling");
      break;
  }
  return v;
}

AssembledProgram ProgramCache::assembleShadeProgram(const BrdfDefinition& brdf, SamplingMode sampling,
                                                    bool constantEnv) const {
  return assembleShadeProgram(brdf, shadeVariant(brdf, sampling, constantEnv), constantEnv);
}

AssembledProgram ProgramCache::assembleShadeProgram(const BrdfDefinition& brdf, const ShadeVariant& variant,
                                                    bool constantEnv, bool preview) const {
  // The file's sampler is compiled in only where it is used: its code would otherwise count
  // towards the features the program needs (brdf_features.cpp).
  BrdfDefinition used = brdf;
  if (!variant.useSampler) used.sampleShader.clear();
  ProgramSpec spec;
  spec.brdf = &used;
  spec.terms = &sources_.terms();  // this renderer's shader tree, whatever else the process loaded
  spec.defines = {variant.define, constantEnv ? "BRDFA_ENV_CONSTANT" : "BRDFA_ENV_CUBEMAP"};
  if (variant.misFileSampler) spec.defines.push_back("BRDFA_MIS_FILE_SAMPLER");
  const BrdfFeatures features = detectFeatures(used);
  if (features.tangentFrame) spec.defines.push_back("BRDFA_TANGENT_FRAME");
  if (features.textures) spec.defines.push_back("BRDFA_TEXTURES");
  if (features.texCoord) spec.defines.push_back("BRDFA_TEXCOORD");
  spec.userChunks.push_back(sources_.get("lib/brdf_inputs.glsl"));
  if (brdf.format == BrdfFormat::Legacy) spec.userChunks.push_back(sources_.get("lib/legacy_inputs.glsl"));
  for (const std::string& piece : shadeLibPieces()) spec.commonChunks.push_back(sources_.get(piece));
  spec.integrator = sources_.get(preview ? "kernels/preview.comp.glsl" : "kernels/shade.comp.glsl");
  return assembleProgram(spec);
}

namespace {
// The line of `brdf`'s text where `name` first appears as a whole word (0: nowhere).
int lineOfName(const BrdfDefinition& brdf, const std::string& name) {
  if (name.empty()) return 0;
  auto search = [&](const std::string& text, int firstLine) {
    int line = firstLine;
    for (size_t at = 0; at < text.size();) {
      size_t end = text.find('\n', at);
      if (end == std::string::npos) end = text.size();
      for (size_t i = text.find(name, at); i != std::string::npos && i + name.size() <= end;
           i = text.find(name, i + 1)) {
        auto ident = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
        if ((i == at || !ident(text[i - 1])) && (i + name.size() == text.size() || !ident(text[i + name.size()])))
          return line;
      }
      at = end + 1;
      ++line;
    }
    return 0;
  };
  if (int line = search(brdf.shader, brdf.shaderFirstLine)) return line;
  return brdf.hasSampler() ? search(brdf.sampleShader, brdf.sampleFirstLine) : 0;
}
}  // namespace

Result<void> ProgramCache::checkResources(const SpirvBinary& code, const BrdfDefinition* brdf) const {
  // The legacy environment name shares the environment's slot (lib/legacy_inputs.glsl).
  static const std::set<std::string> aliases = {"skybox"};
  const std::vector<ForeignResource> foreign = foreignResources(code.words, computeSlots_, aliases);
  if (foreign.empty()) return {};
  Error e =
      makeError(ErrorCode::CompileError,
                "a BRDF file may read its parameters, iTexture0..3 and texCoord, and declare no resources of its "
                "own: it declares " +
                    foreign.front().what + (foreign.front().name.empty() ? "" : " ('" + foreign.front().name + "')"));
  for (const ForeignResource& f : foreign)
    e.diagnostics.push_back(Diagnostic{brdf ? lineOfName(*brdf, f.name) : 0, 0, "error",
                                       "declares " + f.what + (f.name.empty() ? "" : " ('" + f.name + "')") +
                                           ": a BRDF file may not add resources, shared memory, barriers or "
                                           "interface variables"});
  return e;
}

Result<CompileInfo> ProgramCache::compileBrdf(const BrdfDefinition& brdf) {
  // With its sampler when it has one, so a broken sample section is reported at validation.
  AssembledProgram program = assembleShadeProgram(brdf, SamplingMode::Brdf, false);
  CompileInfo info;
  auto code = spirv(ShaderStage::Compute, program.source, &info.cached);
  if (!code) return code.takeError();
  BRDFA_TRY(checkResources(**code, &brdf));
  info.warnings = brdf.warnings;
  if (brdf.hasSampler() && !detectFeatures(brdf).samplerPdf) {
    Diagnostic d;
    d.severity = "warning";
    d.line = brdf.sampleFirstLine;
    d.message =
        "the sample section defines no pdfBRDF(L, V, N, X, Y): sampleBRDF cannot take part in multiple "
        "importance sampling (\"mis\" combines the environment with cosine sampling instead), and the "
        "sampler check cannot run its chi-square test";
    info.warnings.push_back(d);
  }
  info.warnings.insert(info.warnings.end(), (*code)->warnings.begin(), (*code)->warnings.end());
  info.compileMs = info.cached ? 0.0 : (*code)->compileMs;
  return info;
}

Result<ShadeKernels> ProgramCache::shadeKernels(const BrdfDefinition& brdf, const ShadeVariant& variant,
                                                bool constantEnv, bool preview) {
  const AssembledProgram program = assembleShadeProgram(brdf, variant, constantEnv);
  std::optional<AssembledProgram> previewProgram;
  std::future<void> previewGlsl;
  if (preview && compilesAtFirstDispatch() && brdf.format != BrdfFormat::Legacy) {
    bool run = false;  // built and dispatched: it previews itself
    {
      std::lock_guard<std::mutex> lock(kernelMutex_);
      auto it = kernelCache_.find(program.hash);
      run = it != kernelCache_.end() && it->second->dispatched;
    }
    if (!run) {
      previewProgram = assembleShadeProgram(brdf, shadeVariant(brdf, SamplingMode::Cosine, constantEnv), constantEnv,
                                            /*preview=*/true);
      // Into the SPIR-V cache, beside the kernel's compile (spirv() lets one wait for the other).
      previewGlsl = std::async(std::launch::async, [this, source = previewProgram->source] {
        (void)spirv(ShaderStage::Compute, source, nullptr);
      });
    }
  }
  auto kernel = compiledKernel(program);
  if (previewGlsl.valid()) previewGlsl.wait();
  if (!kernel) return kernel.takeError();
  ShadeKernels out{kernel.value(), nullptr};
  if (previewProgram && !out.kernel->dispatched)
    if (auto built = compiledKernel(*previewProgram)) out.preview = built.value();
  return out;
}

Result<int> ProgramCache::preloadFromCache(const BrdfDefinition& brdf) {
  int built = 0;
  for (SamplingMode sampling : {SamplingMode::Mis, SamplingMode::Cosine, SamplingMode::Uniform, SamplingMode::Brdf,
                                SamplingMode::Environment}) {
    if (sampling == SamplingMode::Brdf && !brdf.hasSampler()) continue;  // same program as cosine
    for (bool constantEnv : {false, true}) {
      bool created = false;
      auto kernel =
          compiledKernel(assembleShadeProgram(brdf, sampling, constantEnv), /*compileOnMiss=*/false, &created);
      if (!kernel) {
        if (kernel.error().code == ErrorCode::NotFound) continue;  // never compiled before
        return kernel.takeError();
      }
      built += created ? 1 : 0;
    }
  }
  return built;
}

Result<std::shared_ptr<const ShadeKernel>> ProgramCache::compiledKernel(const AssembledProgram& program,
                                                                        bool compileOnMiss, bool* created) {
  // Held across creation so concurrent requests for one program JIT it once.
  std::lock_guard<std::mutex> lock(kernelMutex_);
  auto it = kernelCache_.find(program.hash);
  if (it != kernelCache_.end()) return it->second;
  auto code = spirv(ShaderStage::Compute, program.source, nullptr, compileOnMiss);
  if (!code) return code.takeError();
  BRDFA_TRY(checkResources(**code, nullptr));
  const uint64_t spirvBytes = (*code)->words.size() * sizeof(uint32_t);
  MemoryReservation memory;
  {
    const uint64_t bytes = kPipelineBytesEstimate + spirvBytes;
    BRDFA_TRY(ledger_.reserve(MemoryUse::Programs, bytes, "building a program", shrinker_({.programs = true})));
    memory = MemoryReservation(&ledger_, MemoryUse::Programs, bytes);
  }
  auto kernel = createComputeKernel((*code)->words);
  if (!kernel) return kernel.takeError();
  ++pipelinesCreated_;
  if (created) *created = true;
  auto compiled = std::make_shared<ShadeKernel>();
  compiled->kernel = std::move(kernel.value());
  compiled->params = program.params;
  compiled->programHash = program.hash;
  compiled->spirvBytes = spirvBytes;
  compiled->memory = std::move(memory);
  kernelCache_.emplace(program.hash, compiled);
  kernelOrder_.push_back(program.hash);
  evictOldest(kernelCache_, kernelOrder_);
  return std::shared_ptr<const ShadeKernel>(compiled);
}

AssembledProgram ProgramCache::assembleCheckProgram(const BrdfDefinition& brdf, const char* kernel) const {
  ProgramSpec spec;
  spec.brdf = &brdf;
  spec.terms = &sources_.terms();
  const BrdfFeatures features = detectFeatures(brdf);
  if (features.textures) spec.defines.push_back("BRDFA_TEXTURES");
  if (features.samplerPdf) spec.defines.push_back("BRDFA_HAS_PDF");    // check_sampler: chi-square test
  if (brdf.hasSampler()) spec.defines.push_back("BRDFA_HAS_SAMPLER");  // lib/albedo.glsl: importance sampling
  spec.userChunks.push_back(sources_.get("lib/brdf_inputs.glsl"));
  for (const char* piece : {"lib/bindings.glsl", "lib/random.glsl", "lib/sampling.glsl",
                            "lib/environment_sampling.glsl", "lib/albedo.glsl"})
    spec.commonChunks.push_back(sources_.get(piece));
  spec.integrator = sources_.get(std::string("kernels/") + kernel);
  return assembleProgram(spec);
}

void ProgramCache::addCounters(RendererCounters& c) const {
  c.glslCompiles = glslCompiles_.load();
  c.glslCompileErrors = glslCompileErrors_.load();
  c.compileTime = compileTime_.snapshot();
  c.spirvCacheHits = spirvCacheHits_.load();
  c.spirvDiskHits = spirvDiskHits_.load();
  c.pipelinesCreated = pipelinesCreated_.load();
}

void ProgramCache::dropUnused(uint64_t needed, bool kernelLockHeld, uint64_t& freed, int& programs, int& spirvModules) {
  underFreeLock(kernelMutex_, kernelLockHeld, [&] {
    dropUnusedEntries(kernelCache_, kernelOrder_, needed, freed, programs,
                      [&](uint64_t key) { return kernelCache_.at(key)->memory.bytes(); });
  });
  underFreeLock(spirvMutex_, false, [&] {
    dropUnusedEntries(spirvCache_, spirvOrder_, needed, freed, spirvModules, [&](uint64_t key) {
      const uint64_t bytes = spirvMemory_[key].bytes();
      spirvMemory_.erase(key);
      return bytes;
    });
  });
}

}  // namespace brdfa
