#include "render/local_renderer.h"

#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "analysis/device_checks.h"
#include "assets/environment_preview.h"
#include "assets/meshes.h"
#include "core/worker_process.h"
#include "device/vk_check.h"
#include "render/local_view.h"

namespace brdfa {

namespace {
// What a device process grows by after start that no reservation names (llvmpipe's first
// shading pipelines, the driver's caches), measured between start and a session's first frames
// on lavapipe, with a margin.
constexpr uint64_t kDriverGrowthBytes = 40ull << 20;
// A brdfa-compile-worker's resident size between compiles, with a margin.
constexpr uint64_t kIdleCompileWorkerBytes = 36ull << 20;
// A fixed stage of the preview kernel: texCoord's declaration, the shading pieces, then `extra`.
std::vector<std::string> previewStagePieces(const std::vector<std::string>& extra) {
  std::vector<std::string> pieces{"lib/brdf_inputs.glsl"};
  pieces.insert(pieces.end(), shadeLibPieces().begin(), shadeLibPieces().end());
  pieces.insert(pieces.end(), extra.begin(), extra.end());
  return pieces;
}
}  // namespace

Result<std::shared_ptr<LocalRenderer>> LocalRenderer::create(const RendererOptions& options) {
  std::shared_ptr<LocalRenderer> r(new LocalRenderer());
  BRDFA_TRY(r->init(options));
  return r;
}

Result<void> LocalRenderer::init(const RendererOptions& options) {
  auto diskCache = std::make_unique<SpirvDiskCache>(options.cacheDir, options.loadCache);
  ledger_ = std::make_unique<MemoryLedger>(options.memoryBudgetBytes, options.memoryBudgetLabel);
  const size_t workers =
      options.compileWorkers > 0 ? options.compileWorkers : std::max<size_t>(2, std::thread::hardware_concurrency());
  auto compilePool = std::make_unique<CompilePool>(
      CompilePool::findWorker(), CompileBudget{options.compileSeconds, options.compileMemoryMiB}, workers);
  if (!options.driverCacheDir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.driverCacheDir, ec);
    ::setenv("MESA_SHADER_CACHE_DIR", options.driverCacheDir.c_str(), /*overwrite=*/0);
  }
  auto sources = ShaderSources::load(options.shaderDir);
  if (!sources) return sources.takeError();
  auto ctx = VkContext::create(options);
  if (!ctx) return ctx.takeError();
  ctx_ = std::move(ctx.value());
  profilePasses_ = options.profilePasses;
  hostResolve_ =
      options.resolve == ResolveMode::Host || (options.resolve == ResolveMode::Auto && ctx_->info().type == "cpu");
  layouts_ = std::make_unique<PipelineLayouts>(ctx_->device());
  BRDFA_TRY(layouts_->create());
  auto shrinkerFor = [this](HeldCacheLocks held) { return shrinker(held); };
  programs_ = std::make_unique<ProgramCache>(*ctx_, *ledger_, std::move(sources.value()), std::move(diskCache),
                                             std::move(compilePool), layouts_->compute(), layouts_->computeSlots(),
                                             shrinkerFor);
  assets_ = std::make_unique<AssetCache>(*ctx_, *ledger_, shrinkerFor);
  BRDFA_TRY(createGbufferPipeline());
  BRDFA_TRY(createFixedKernels());
  BRDFA_TRY(assets_->init());
  reserveFixedMemory(options, workers);
  return {};
}

Result<void> LocalRenderer::createFixedKernels() {
  auto resolve = programs_->compileFixedKernel(
      {}, {"lib/bindings.glsl", "lib/gbuffer_encoding.glsl", "lib/tonemap.glsl", "kernels/resolve.comp.glsl"},
      {"GL_KHR_shader_subgroup_arithmetic"});
  if (!resolve) return resolve.takeError();
  resolve_ = std::move(resolve.value());
  for (bool constant : {true, false}) {
    auto bg = programs_->compileFixedKernel(
        {constant ? "BRDFA_ENV_CONSTANT" : "BRDFA_ENV_CUBEMAP"},
        {"lib/bindings.glsl", "lib/gbuffer_encoding.glsl", "lib/environment.glsl", "kernels/background.comp.glsl"});
    if (!bg) return bg.takeError();
    (constant ? backgroundConstant_ : backgroundCube_) = std::move(bg.value());
    if (!compilesAtFirstDispatch()) continue;  // the preview kernel's stages: CPU devices only
    // Always the tangent frame and texCoord: the setup serves every BRDF (preview_setup.comp.glsl).
    auto setup = programs_->compileFixedKernel(
        {constant ? "BRDFA_ENV_CONSTANT" : "BRDFA_ENV_CUBEMAP", "BRDFA_TANGENT_FRAME", "BRDFA_TEXCOORD",
         "BRDFA_PREVIEW_LOG2_CELLS " + std::to_string(kPreviewLog2Cells)},
        previewStagePieces({"lib/environment_preview.glsl", "kernels/preview_setup.comp.glsl"}));
    if (!setup) return setup.takeError();
    (constant ? previewSetupConstant_ : previewSetupCube_) = std::move(setup.value());
  }
  if (compilesAtFirstDispatch()) {
    // Writes through lib/shade_pixel.glsl, which needs the pieces before it (the environment
    // kind does not matter to the writes).
    auto scatter = programs_->compileFixedKernel({"BRDFA_ENV_CONSTANT"},
                                                 previewStagePieces({"kernels/preview_scatter.comp.glsl"}));
    if (!scatter) return scatter.takeError();
    previewScatter_ = std::move(scatter.value());
  }
  return {};
}

void LocalRenderer::reserveFixedMemory(const RendererOptions& options, size_t workers) {
  // What the process holds now (driver, LLVM, fixed pipelines, and what it grows by unasked)
  // and its compile workers idle are paid before any session, once for this process and once
  // for each idle copy kept ready; what the compile workers may grow to while compiling, once.
  const uint64_t own = worker_process::residentBytes(::getpid()) + kDriverGrowthBytes;
  const uint64_t copies = 1 + uint64_t(options.spareProcesses);
  const uint64_t compileCap = uint64_t(options.compileMemoryMiB) << 20;
  const uint64_t idle = std::min(kIdleCompileWorkerBytes, compileCap);
  ledger_->add(MemoryUse::Fixed, (own + workers * idle) * copies);
  ledger_->add(MemoryUse::Compiles, workers * (compileCap - idle));
  // This process may grow into whatever of the budget the other processes do not hold.
  const uint64_t others = (own + workers * idle) * copies - own + workers * (compileCap - idle);
  processMemoryLimit_ =
      options.memoryBudgetBytes ? options.memoryBudgetBytes - std::min(others, options.memoryBudgetBytes) : 0;
}

LocalRenderer::~LocalRenderer() {
  if (!ctx_) return;
  VkDevice d = ctx_->device();
  vkDeviceWaitIdle(d);
  programs_.reset();
  assets_.reset();
  resolve_.reset();
  backgroundConstant_.reset();
  backgroundCube_.reset();
  previewSetupConstant_.reset();
  previewSetupCube_.reset();
  previewScatter_.reset();
  if (gbufferPipeline_) vkDestroyPipeline(d, gbufferPipeline_, nullptr);
  layouts_.reset();
}

Result<void> LocalRenderer::createGbufferPipeline() {
  VkDevice d = ctx_->device();
  auto vs = programs_->spirv(ShaderStage::Vertex, programs_->sources().assembleFixed({}, {"kernels/gbuffer.vert.glsl"}),
                             nullptr);
  if (!vs) return vs.takeError();
  auto fs = programs_->spirv(
      ShaderStage::Fragment,
      programs_->sources().assembleFixed({}, {"lib/gbuffer_encoding.glsl", "kernels/gbuffer.frag.glsl"}), nullptr);
  if (!fs) return fs.takeError();
  VkShaderModule modules[2] = {};
  const std::vector<uint32_t>* code[2] = {&(*vs)->words, &(*fs)->words};
  for (int i = 0; i < 2; ++i) {
    VkShaderModuleCreateInfo mci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    mci.codeSize = code[i]->size() * 4;
    mci.pCode = code[i]->data();
    VkResult r = vkCreateShaderModule(d, &mci, nullptr, &modules[i]);
    if (r != VK_SUCCESS) {
      if (modules[0]) vkDestroyShaderModule(d, modules[0], nullptr);
      return vkError(r, "vkCreateShaderModule");
    }
  }
  VkPipelineShaderStageCreateInfo stages[2] = {};
  for (int i = 0; i < 2; ++i) {
    stages[i].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    stages[i].stage = i == 0 ? VK_SHADER_STAGE_VERTEX_BIT : VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[i].module = modules[i];
    stages[i].pName = "main";
  }
  VkVertexInputBindingDescription binding{0, sizeof(Vertex), VK_VERTEX_INPUT_RATE_VERTEX};
  VkVertexInputAttributeDescription attrs[4] = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, position)},
                                                {1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, normal)},
                                                {2, 0, VK_FORMAT_R32G32_SFLOAT, offsetof(Vertex, texCoord)},
                                                {3, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(Vertex, tangent)}};
  VkPipelineVertexInputStateCreateInfo vi{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  vi.vertexBindingDescriptionCount = 1;
  vi.pVertexBindingDescriptions = &binding;
  vi.vertexAttributeDescriptionCount = 4;
  vi.pVertexAttributeDescriptions = attrs;
  VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  vp.viewportCount = 1;
  vp.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  rs.polygonMode = VK_POLYGON_MODE_FILL;
  rs.cullMode = VK_CULL_MODE_NONE;  // two-sided: open meshes are seen from both sides
  // Meshes wind counter-clockwise seen from outside; the projection flips Y so the image is
  // upright, which keeps that winding counter-clockwise on screen.
  rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  rs.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  ds.depthTestEnable = VK_TRUE;
  ds.depthWriteEnable = VK_TRUE;
  ds.depthCompareOp = VK_COMPARE_OP_LESS;
  VkPipelineColorBlendAttachmentState blend[2] = {};
  for (auto& b : blend) b.colorWriteMask = 0xF;
  VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  cb.attachmentCount = 2;
  cb.pAttachments = blend;
  VkDynamicState dyn[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  VkPipelineDynamicStateCreateInfo dy{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dy.dynamicStateCount = 2;
  dy.pDynamicStates = dyn;
  VkGraphicsPipelineCreateInfo gpi{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  gpi.stageCount = 2;
  gpi.pStages = stages;
  gpi.pVertexInputState = &vi;
  gpi.pInputAssemblyState = &ia;
  gpi.pViewportState = &vp;
  gpi.pRasterizationState = &rs;
  gpi.pMultisampleState = &ms;
  gpi.pDepthStencilState = &ds;
  gpi.pColorBlendState = &cb;
  gpi.pDynamicState = &dy;
  gpi.layout = layouts_->raster();
  gpi.renderPass = layouts_->gbufferPass();
  VkResult r = vkCreateGraphicsPipelines(d, VK_NULL_HANDLE, 1, &gpi, nullptr, &gbufferPipeline_);
  for (VkShaderModule m : modules) vkDestroyShaderModule(d, m, nullptr);
  if (r != VK_SUCCESS) return vkError(r, "vkCreateGraphicsPipelines");
  return {};
}

Result<BrdfCheckReport> LocalRenderer::checkBrdf(const BrdfDefinition& brdf) {
  return analysis::checkBrdf(checkDevice(), brdf);
}

Result<SamplerCheckReport> LocalRenderer::checkSampler(const BrdfDefinition& brdf) {
  return analysis::checkSampler(checkDevice(), brdf);
}

Result<EnvironmentSamplerReport> LocalRenderer::checkEnvironmentSampler(const std::string& environment) {
  return analysis::checkEnvironmentSampler(checkDevice(), environment);
}

Result<std::vector<Vec3>> LocalRenderer::evaluateBrdf(const BrdfDefinition& brdf,
                                                      const std::vector<ParamSetting>& settings,
                                                      const std::vector<DirectionPair>& pairs) {
  return analysis::evaluateBrdf(checkDevice(), brdf, settings, pairs);
}

Result<std::vector<AlbedoEstimate>> LocalRenderer::estimateAlbedo(const BrdfDefinition& brdf,
                                                                  const std::vector<ParamSetting>& settings,
                                                                  const std::vector<Vec3>& views,
                                                                  uint32_t samplesPerView) {
  return analysis::estimateAlbedo(checkDevice(), brdf, settings, views, samplesPerView);
}

RendererCounters LocalRenderer::counters() const {
  RendererCounters c;
  programs_->addCounters(c);
  c.memory = ledger_->usage();
  return c;
}

Result<void> LocalRenderer::exchangeViewMemory(uint64_t oldBytes, uint64_t newBytes, const std::string& what,
                                               std::string* dropped) {
  return ledger_->exchange(MemoryUse::RenderTargets, oldBytes, newBytes, what, shrinker({}), dropped);
}

std::string LocalRenderer::dropUnusedCaches(uint64_t needed, HeldCacheLocks held) {
  uint64_t freed = 0;
  int programs = 0, spirv = 0;
  std::vector<std::string> assets;
  // A lock this thread does not hold is taken only if it is free: a shrink never waits.
  programs_->dropUnused(needed, held.programs, freed, programs, spirv);
  assets_->dropUnused(needed, held.assets, freed, assets);
  if (freed == 0) return {};
  std::string what;
  auto add = [&](const std::string& part) { what += (what.empty() ? "" : ", ") + part; };
  if (programs) add(std::to_string(programs) + " cached program" + (programs == 1 ? "" : "s"));
  if (spirv) add(std::to_string(spirv) + " cached SPIR-V module" + (spirv == 1 ? "" : "s"));
  for (const std::string& name : assets) add("the unused asset '" + name + "'");
  what = "dropped " + what + " (" + mebibytesText(freed) +
         ") to stay within the memory budget; they are rebuilt when used";
  ledger_->noteDropped(freed, what);
  return what;
}

Result<std::unique_ptr<RenderView>> LocalRenderer::createView() {
  auto view = std::make_unique<LocalView>(shared_from_this());
  BRDFA_TRY(view->init());
  return std::unique_ptr<RenderView>(std::move(view));
}

}  // namespace brdfa
