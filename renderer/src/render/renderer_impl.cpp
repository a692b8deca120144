#include "render/renderer_impl.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "assets/environment_maps.h"
#include "assets/environment_preview.h"
#include "assets/environment_sampling.h"
#include "assets/meshes.h"
#include "assets/obj_loader.h"
#include "core/worker_process.h"
#include "device/device_activity.h"
#include "device/vk_check.h"
#include "programs/brdf_features.h"
#include "programs/spirv_resources.h"
#include "render/render_view.h"

namespace brdfa {

namespace {
constexpr size_t kMaxCachedPrograms = 256;
// What one built shading pipeline is counted at against the memory budget: the worker's
// resident memory grew by 3.8 MiB a pipeline over 13 pipelines on lavapipe (LLVM's machine code
// and its bookkeeping); a GPU driver keeps less on the host.
constexpr uint64_t kPipelineBytesEstimate = 4ull << 20;
// What a device process grows by after start that no reservation names (llvmpipe's first
// shading pipelines, the driver's caches): 38 MiB between start and the first frames of a
// session at 128^2 (lavapipe, Mesa 22.3).
constexpr uint64_t kDriverGrowthBytes = 40ull << 20;
// A brdfa-compile-worker between compiles: 33 MiB resident (glslang 11.13, Debian 12).
constexpr uint64_t kIdleCompileWorkerBytes = 36ull << 20;
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
// The shaders/lib pieces of a shading program after the BRDF, in order (each may call those
// before it): the shade kernel's, and the preview kernel's fixed stages'.
const std::vector<std::string> kShadeLibPieces = {"lib/bindings.glsl",      "lib/gbuffer_encoding.glsl",
                                                  "lib/random.glsl",        "lib/frame.glsl",
                                                  "lib/sampling.glsl",      "lib/environment.glsl",
                                                  "lib/environment_sampling.glsl", "lib/shade_pixel.glsl"};
// A fixed stage of the preview kernel: texCoord's declaration, the shading pieces, then `extra`.
std::vector<std::string> previewStagePieces(const std::vector<std::string>& extra) {
  std::vector<std::string> pieces{"lib/brdf_inputs.glsl"};
  pieces.insert(pieces.end(), kShadeLibPieces.begin(), kShadeLibPieces.end());
  pieces.insert(pieces.end(), extra.begin(), extra.end());
  return pieces;
}

template <class Map>
void evictOldest(Map& map, std::deque<uint64_t>& order) {
  while (order.size() > kMaxCachedPrograms) {
    map.erase(order.front());
    order.pop_front();
  }
}
}  // namespace

Result<std::shared_ptr<RendererImpl>> RendererImpl::create(const RendererOptions& options) {
  std::shared_ptr<RendererImpl> r(new RendererImpl());
  BRDFA_TRY(r->init(options));
  return r;
}

Result<void> RendererImpl::init(const RendererOptions& options) {
  diskCache_ = std::make_unique<SpirvDiskCache>(options.cacheDir, options.loadCache);
  ledger_ = std::make_unique<MemoryLedger>(options.memoryBudgetBytes, options.memoryBudgetLabel);
  const size_t workers = options.compileWorkers > 0
                             ? options.compileWorkers
                             : std::max<size_t>(2, std::thread::hardware_concurrency());
  compilePool_ = std::make_unique<CompilePool>(CompilePool::findWorker(),
                                               CompileBudget{options.compileSeconds, options.compileMemoryMiB}, workers);
  if (!options.driverCacheDir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.driverCacheDir, ec);
    ::setenv("MESA_SHADER_CACHE_DIR", options.driverCacheDir.c_str(), /*overwrite=*/0);
  }
  auto sources = ShaderSources::load(options.shaderDir);
  if (!sources) return sources.takeError();
  sources_ = std::move(sources.value());
  auto ctx = VkContext::create(options);
  if (!ctx) return ctx.takeError();
  ctx_ = std::move(ctx.value());
  profilePasses_ = options.profilePasses;
  hostResolve_ = options.resolve == ResolveMode::Host ||
                 (options.resolve == ResolveMode::Auto && ctx_->info().type == "cpu");
  BRDFA_TRY(createLayouts());
  BRDFA_TRY(createGbufferPipeline());

  auto resolve = compileFixedKernel({}, {"lib/bindings.glsl", "lib/gbuffer_encoding.glsl", "lib/tonemap.glsl", "kernels/resolve.comp.glsl"},
                                    {"GL_KHR_shader_subgroup_arithmetic"});
  if (!resolve) return resolve.takeError();
  resolve_ = std::move(resolve.value());
  for (bool constant : {true, false}) {
    auto bg = compileFixedKernel({constant ? "BRDFA_ENV_CONSTANT" : "BRDFA_ENV_CUBEMAP"},
                                 {"lib/bindings.glsl", "lib/gbuffer_encoding.glsl", "lib/environment.glsl", "kernels/background.comp.glsl"});
    if (!bg) return bg.takeError();
    (constant ? backgroundConstant_ : backgroundCube_) = std::move(bg.value());
    if (!compilesAtFirstDispatch()) continue;  // the preview kernel's stages: CPU devices only
    // Always the tangent frame and texCoord: the setup serves every BRDF (preview_setup.comp.glsl).
    auto setup = compileFixedKernel(
        {constant ? "BRDFA_ENV_CONSTANT" : "BRDFA_ENV_CUBEMAP", "BRDFA_TANGENT_FRAME", "BRDFA_TEXCOORD",
         "BRDFA_PREVIEW_LOG2_CELLS " + std::to_string(kPreviewLog2Cells)},
        previewStagePieces({"lib/environment_preview.glsl", "kernels/preview_setup.comp.glsl"}));
    if (!setup) return setup.takeError();
    (constant ? previewSetupConstant_ : previewSetupCube_) = std::move(setup.value());
  }
  if (compilesAtFirstDispatch()) {
    // Writes through lib/shade_pixel.glsl, which needs the pieces before it (the environment
    // kind does not matter to the writes).
    auto scatter = compileFixedKernel({"BRDFA_ENV_CONSTANT"}, previewStagePieces({"kernels/preview_scatter.comp.glsl"}));
    if (!scatter) return scatter.takeError();
    previewScatter_ = std::move(scatter.value());
  }

  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = VK_FILTER_LINEAR;
  sci.minFilter = VK_FILTER_LINEAR;
  sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  sci.maxLod = 0.0f;
  BRDFA_VK_TRY(vkCreateSampler(ctx_->device(), &sci, nullptr, &envSampler_));

  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  BRDFA_VK_TRY(vkCreateSampler(ctx_->device(), &sci, nullptr, &textureSampler_));

  ImageSpec white;
  white.format = VK_FORMAT_R8G8B8A8_UNORM;
  white.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  auto image = Image::create(*ctx_, white);
  if (!image) return image.takeError();
  whiteTexture_ = std::move(image.value());
  const uint32_t texel = 0xffffffffu;
  BRDFA_TRY(uploadImage(*ctx_, whiteTexture_, &texel, sizeof texel));
  // What the process holds now (driver, LLVM, fixed pipelines: ~70 MiB on lavapipe, and what it
  // grows by unasked), and its
  // compile workers idle are paid before any session, once for this process and once for each
  // idle copy kept ready; what the compile workers may grow to while compiling, once.
  const uint64_t own = worker_process::residentBytes(::getpid()) + kDriverGrowthBytes;
  const uint64_t copies = 1 + uint64_t(options.spareProcesses);
  const uint64_t compileCap = uint64_t(options.compileMemoryMiB) << 20;
  const uint64_t idle = std::min(kIdleCompileWorkerBytes, compileCap);
  ledger_->add(MemoryUse::Fixed, (own + workers * idle) * copies);
  ledger_->add(MemoryUse::Compiles, workers * (compileCap - idle));
  // This process may grow into whatever of the budget the other processes do not hold.
  const uint64_t others = (own + workers * idle) * copies - own + workers * (compileCap - idle);
  processMemoryLimit_ = options.memoryBudgetBytes ? options.memoryBudgetBytes - std::min(others, options.memoryBudgetBytes) : 0;
  return {};
}

void RendererImpl::writeTextures(VkDescriptorSet objectSet,
                                 const std::shared_ptr<const GpuTexture> (&textures)[kMaxTextures]) const {
  std::array<VkDescriptorImageInfo, kMaxTextures> info{};
  std::array<VkWriteDescriptorSet, kMaxTextures> w{};
  for (uint32_t i = 0; i < kMaxTextures; ++i) {
    info[i] = {textureSampler_, textures[i] ? textures[i]->image.view() : whiteTexture_.view(),
               VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    w[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, objectSet, 2 + i, 0, 1,
            VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, &info[i], nullptr, nullptr};
  }
  vkUpdateDescriptorSets(ctx_->device(), static_cast<uint32_t>(w.size()), w.data(), 0, nullptr);
}

void RendererImpl::writeDefaultTextures(VkDescriptorSet objectSet) const {
  const std::shared_ptr<const GpuTexture> none[kMaxTextures];
  writeTextures(objectSet, none);
}

RendererImpl::~RendererImpl() {
  if (!ctx_) return;
  VkDevice d = ctx_->device();
  vkDeviceWaitIdle(d);
  kernelCache_.clear();
  environments_.clear();
  meshes_.clear();
  textures_.clear();
  resolve_.reset();
  backgroundConstant_.reset();
  backgroundCube_.reset();
  previewSetupConstant_.reset();
  previewSetupCube_.reset();
  previewScatter_.reset();
  if (envSampler_) vkDestroySampler(d, envSampler_, nullptr);
  if (textureSampler_) vkDestroySampler(d, textureSampler_, nullptr);
  whiteTexture_ = Image();
  if (gbufferPipeline_) vkDestroyPipeline(d, gbufferPipeline_, nullptr);
  if (gbufferPass_) vkDestroyRenderPass(d, gbufferPass_, nullptr);
  if (computeLayout_) vkDestroyPipelineLayout(d, computeLayout_, nullptr);
  if (rasterLayout_) vkDestroyPipelineLayout(d, rasterLayout_, nullptr);
  if (viewSetLayout_) vkDestroyDescriptorSetLayout(d, viewSetLayout_, nullptr);
  if (objectSetLayout_) vkDestroyDescriptorSetLayout(d, objectSetLayout_, nullptr);
}

Result<void> RendererImpl::createLayouts() {
  VkDevice d = ctx_->device();
  // Set 0: one view's G-buffer, accumulators, counters, environment and outputs
  // (bindings as in shaders/lib/bindings.glsl).
  const std::array<std::pair<uint32_t, VkDescriptorType>, 12> viewBindings = {{
      {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},         {3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
      {4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},         {5, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
      {6, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},         {7, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
      {8, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},         {9, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER},
      {10, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER},  {11, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER},
      {12, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},        {13, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER}}};
  std::array<VkDescriptorSetLayoutBinding, viewBindings.size()> view{};
  for (size_t i = 0; i < view.size(); ++i)
    view[i] = {viewBindings[i].first, viewBindings[i].second, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo li{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  li.bindingCount = static_cast<uint32_t>(view.size());
  li.pBindings = view.data();
  BRDFA_VK_TRY(vkCreateDescriptorSetLayout(d, &li, nullptr, &viewSetLayout_));

  // Set 1: one object's BRDF parameters (shading), transform (raster) and textures
  // iTexture0..3 (shading; lib/brdf_inputs.glsl).
  std::array<VkDescriptorSetLayoutBinding, 6> object{};
  object[0] = {0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  object[1] = {1, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, nullptr};
  for (uint32_t t = 0; t < 4; ++t)
    object[2 + t] = {2 + t, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
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
    att[i].finalLayout = color ? VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL : VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
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
  deps[0] = {VK_SUBPASS_EXTERNAL, 0, VK_PIPELINE_STAGE_TRANSFER_BIT,
             VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT, 0,
             VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, 0};
  // The written targets are visible to the copy into the G-buffer storage buffer.
  deps[1] = {0, VK_SUBPASS_EXTERNAL, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
             VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
             VK_ACCESS_TRANSFER_READ_BIT, 0};
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

Result<void> RendererImpl::createGbufferPipeline() {
  VkDevice d = ctx_->device();
  auto vs = spirv(ShaderStage::Vertex, sources_.assembleFixed({}, {"kernels/gbuffer.vert.glsl"}), nullptr);
  if (!vs) return vs.takeError();
  auto fs = spirv(ShaderStage::Fragment, sources_.assembleFixed({}, {"lib/gbuffer_encoding.glsl", "kernels/gbuffer.frag.glsl"}), nullptr);
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
  VkVertexInputAttributeDescription attrs[4] = {
      {0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Vertex, position)},
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
  gpi.layout = rasterLayout_;
  gpi.renderPass = gbufferPass_;
  VkResult r = vkCreateGraphicsPipelines(d, VK_NULL_HANDLE, 1, &gpi, nullptr, &gbufferPipeline_);
  for (VkShaderModule m : modules) vkDestroyShaderModule(d, m, nullptr);
  if (r != VK_SUCCESS) return vkError(r, "vkCreateGraphicsPipelines");
  return {};
}

Result<std::unique_ptr<ComputeKernel>> RendererImpl::createComputeKernel(const std::vector<uint32_t>& code) {
  VkDevice d = ctx_->device();
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

Result<std::unique_ptr<ComputeKernel>> RendererImpl::compileFixedKernel(const std::vector<std::string>& defines,
                                                                        const std::vector<std::string>& pieces,
                                                                        const std::vector<std::string>& extensions) {
  for (const auto& p : pieces)
    if (sources_.get(p).empty()) return makeError(ErrorCode::NotFound, "shader source missing: " + p);
  auto code = spirv(ShaderStage::Compute, sources_.assembleFixed(defines, pieces, extensions), nullptr);
  if (!code) return code.takeError();
  return createComputeKernel((*code)->words);
}

Result<std::shared_ptr<const SpirvBinary>> RendererImpl::spirv(ShaderStage stage, const std::string& source,
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
    RendererImpl* r;
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
  if (!ledger_->reserve(MemoryUse::Programs, bytes, "a SPIR-V cache entry")) return shared;
  MemoryReservation held(ledger_.get(), MemoryUse::Programs, bytes);
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
    case SamplingMode::Cosine: v.define = "BRDFA_SAMPLING_COSINE"; v.estimator = "cosine"; break;
    case SamplingMode::Uniform: v.define = "BRDFA_SAMPLING_UNIFORM"; v.estimator = "uniform"; break;
    case SamplingMode::Brdf: brdfSide(false); break;
    case SamplingMode::Environment: v.define = "BRDFA_SAMPLING_ENVIRONMENT"; v.estimator = "environment"; break;
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
        v.warnings.push_back("sampleBRDF without pdfBRDF cannot take part in MIS: mis combines the environment "
                             "with cosine sampling");
      break;
  }
  return v;
}

AssembledProgram RendererImpl::assembleShadeProgram(const BrdfDefinition& brdf, SamplingMode sampling,
                                                    bool constantEnv) const {
  return assembleShadeProgram(brdf, shadeVariant(brdf, sampling, constantEnv), constantEnv);
}

AssembledProgram RendererImpl::assembleShadeProgram(const BrdfDefinition& brdf, const ShadeVariant& variant,
                                                    bool constantEnv, bool preview) const {
  // The file's sampler is compiled in only where it is used: its code would otherwise count
  // towards the features the program needs (brdf_features.cpp).
  BrdfDefinition used = brdf;
  if (!variant.useSampler) used.sampleShader.clear();
  ProgramSpec spec;
  spec.brdf = &used;
  spec.defines = {variant.define, constantEnv ? "BRDFA_ENV_CONSTANT" : "BRDFA_ENV_CUBEMAP"};
  if (variant.misFileSampler) spec.defines.push_back("BRDFA_MIS_FILE_SAMPLER");
  const BrdfFeatures features = detectFeatures(used);
  if (features.tangentFrame) spec.defines.push_back("BRDFA_TANGENT_FRAME");
  if (features.textures) spec.defines.push_back("BRDFA_TEXTURES");
  if (features.texCoord) spec.defines.push_back("BRDFA_TEXCOORD");
  spec.userChunks.push_back(sources_.get("lib/brdf_inputs.glsl"));
  if (brdf.format == BrdfFormat::Legacy) spec.userChunks.push_back(sources_.get("lib/legacy_inputs.glsl"));
  for (const std::string& piece : kShadeLibPieces) spec.commonChunks.push_back(sources_.get(piece));
  spec.integrator = sources_.get(preview ? "kernels/preview.comp.glsl" : "kernels/shade.comp.glsl");
  return assembleProgram(spec);
}

// The line of `brdf`'s text where `name` first appears as a whole word (0: nowhere).
static int lineOfName(const BrdfDefinition& brdf, const std::string& name) {
  if (name.empty()) return 0;
  auto search = [&](const std::string& text, int firstLine) {
    int line = firstLine;
    for (size_t at = 0; at < text.size();) {
      size_t end = text.find('\n', at);
      if (end == std::string::npos) end = text.size();
      for (size_t i = text.find(name, at); i != std::string::npos && i + name.size() <= end; i = text.find(name, i + 1)) {
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

Result<void> RendererImpl::checkResources(const SpirvBinary& code, const BrdfDefinition* brdf) const {
  // The legacy environment name shares the environment's slot (lib/legacy_inputs.glsl).
  static const std::set<std::string> aliases = {"skybox"};
  const std::vector<ForeignResource> foreign = foreignResources(code.words, computeSlots_, aliases);
  if (foreign.empty()) return {};
  Error e = makeError(ErrorCode::CompileError,
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

Result<CompileInfo> RendererImpl::compileBrdf(const BrdfDefinition& brdf) {
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
    d.message = "the sample section defines no pdfBRDF(L, V, N, X, Y): sampleBRDF cannot take part in multiple "
                "importance sampling (\"mis\" combines the environment with cosine sampling instead), and the "
                "sampler check cannot run its chi-square test";
    info.warnings.push_back(d);
  }
  info.warnings.insert(info.warnings.end(), (*code)->warnings.begin(), (*code)->warnings.end());
  info.compileMs = info.cached ? 0.0 : (*code)->compileMs;
  return info;
}

Result<RendererImpl::ShadeKernels> RendererImpl::shadeKernels(const BrdfDefinition& brdf, const ShadeVariant& variant,
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
      previewGlsl = std::async(std::launch::async,
                               [this, source = previewProgram->source] { (void)spirv(ShaderStage::Compute, source, nullptr); });
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

Result<int> RendererImpl::preloadFromCache(const BrdfDefinition& brdf) {
  int built = 0;
  for (SamplingMode sampling : {SamplingMode::Mis, SamplingMode::Cosine, SamplingMode::Uniform, SamplingMode::Brdf,
                                SamplingMode::Environment}) {
    if (sampling == SamplingMode::Brdf && !brdf.hasSampler()) continue;  // same program as cosine
    for (bool constantEnv : {false, true}) {
      bool created = false;
      auto kernel = compiledKernel(assembleShadeProgram(brdf, sampling, constantEnv), /*compileOnMiss=*/false, &created);
      if (!kernel) {
        if (kernel.error().code == ErrorCode::NotFound) continue;  // never compiled before
        return kernel.takeError();
      }
      built += created ? 1 : 0;
    }
  }
  return built;
}

Result<std::shared_ptr<const ShadeKernel>> RendererImpl::compiledKernel(const AssembledProgram& program,
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
    BRDFA_TRY(ledger_->reserve(MemoryUse::Programs, bytes, "building a program", shrinker({.kernels = true})));
    memory = MemoryReservation(ledger_.get(), MemoryUse::Programs, bytes);
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

AssembledProgram RendererImpl::assembleCheckProgram(const BrdfDefinition& brdf, const char* kernel) const {
  ProgramSpec spec;
  spec.brdf = &brdf;
  const BrdfFeatures features = detectFeatures(brdf);
  if (features.textures) spec.defines.push_back("BRDFA_TEXTURES");
  if (features.samplerPdf) spec.defines.push_back("BRDFA_HAS_PDF");  // check_sampler: chi-square test
  if (brdf.hasSampler()) spec.defines.push_back("BRDFA_HAS_SAMPLER");  // lib/albedo.glsl: importance sampling
  spec.userChunks.push_back(sources_.get("lib/brdf_inputs.glsl"));
  for (const char* piece : {"lib/bindings.glsl", "lib/random.glsl", "lib/sampling.glsl", "lib/environment_sampling.glsl",
                            "lib/albedo.glsl"})
    spec.commonChunks.push_back(sources_.get(piece));
  spec.integrator = sources_.get(std::string("kernels/") + kernel);
  return assembleProgram(spec);
}

namespace {

Result<Buffer> deviceBufferWith(VkContext& ctx, const void* bytes, VkDeviceSize size, VkBufferUsageFlags usage) {
  auto staging = Buffer::create(ctx, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true);
  if (!staging) return staging.takeError();
  std::memcpy(staging->mapped(), bytes, size);
  auto buffer = Buffer::create(ctx, size, usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false);
  if (!buffer) return buffer.takeError();
  auto cmd = CommandContext::create(ctx);
  if (!cmd) return cmd.takeError();
  auto cb = cmd->begin();
  if (!cb) return cb.takeError();
  VkBufferCopy region{0, 0, size};
  vkCmdCopyBuffer(*cb, staging->handle(), buffer->handle(), 1, &region);
  memoryBarrier(*cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                VK_PIPELINE_STAGE_VERTEX_INPUT_BIT, VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_INDEX_READ_BIT);
  BRDFA_TRY(cmd->submitAndWait());
  return buffer;
}

Result<std::string> readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(ErrorCode::NotFound, "asset file is missing: " + path);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in.good() && !in.eof()) return makeError(ErrorCode::Internal, "cannot read asset file " + path);
  return text.str();
}

// A registered asset's file failed to decode although it passed inspectAsset when stored
// (edited or damaged on disk): a scene error naming the asset, not a crash.
Error assetError(Error e, AssetKind kind, const std::string& name) {
  e.message = std::string(assetKindName(kind)) + " '" + name + "': " + e.message;
  return e;
}

// Stored assets passed inspectAsset, with the configured limits, when they were stored: read
// back, they are decoded without limits.
constexpr AssetLimits kUnlimited{~0ull, ~0ull, ~0ull};

// Looks `name` up in a cache of weak references, dropping the entry when it has expired.
template <class T>
std::shared_ptr<const T> lockCached(std::map<std::string, std::weak_ptr<const T>>& cache, const std::string& name) {
  auto it = cache.find(name);
  if (it == cache.end()) return nullptr;
  auto strong = it->second.lock();
  if (!strong) cache.erase(it);
  return strong;
}

// What an asset's data holds on the host (decoded), and what its upload makes on the device:
// the budget's figures for them (upper bounds where the device form is chosen at upload).
uint64_t hostBytes(const MeshData& m) { return m.vertices.size() * sizeof(Vertex) + m.indices.size() * 4; }
uint64_t deviceBytes(const MeshData& m) { return hostBytes(m); }
uint64_t hostBytes(const TextureData& t) { return t.rgba8.size(); }
uint64_t deviceBytes(const TextureData& t) { return uint64_t(t.width) * t.height * 4; }
uint64_t hostBytes(const EnvironmentData& e) { return e.texels.size() * sizeof(float); }
uint64_t deviceBytes(const EnvironmentData& e) {
  const uint64_t cube = uint64_t(e.faceSize) * e.faceSize * 6 * 4 * sizeof(uint16_t);  // RGBA16F
  // The sampling table, on the device and again on the host (EnvironmentDistribution).
  const uint64_t table = e.constant ? 0 : (2 * (6ull * kMaxCellsPerEdge * kMaxCellsPerEdge + 1) + kPreviewEntries) * 8;
  return cube + table;
}

}  // namespace

Result<void> RendererImpl::registerAsset(const std::string& name, AssetKind kind, const std::string& path) {
  if (name.empty()) return makeError(ErrorCode::InvalidArgument, "an asset needs a name");
  std::vector<std::string> builtins = kind == AssetKind::Mesh      ? builtinMeshNames()
                                      : kind == AssetKind::Texture ? builtinTextureNames()
                                                                   : builtinEnvironmentNames();
  if (std::find(builtins.begin(), builtins.end(), name) != builtins.end())
    return makeError(ErrorCode::InvalidArgument, "'" + name + "' is a built-in " + assetKindName(kind) + " name");
  std::lock_guard<std::mutex> lock(assetMutex_);
  registered_[{kind, name}] = path;
  // Later scenes load the new file; views already holding the old one keep it.
  if (kind == AssetKind::Mesh) uploadedMeshes_.erase(name);
  if (kind == AssetKind::Environment) uploadedEnvironments_.erase(name);
  if (kind == AssetKind::Texture) {
    uploadedTextures_.erase(name + "|srgb");
    uploadedTextures_.erase(name + "|linear");
  }
  return {};
}

Result<std::string> RendererImpl::registeredPath(AssetKind kind, const std::string& name) const {
  auto it = registered_.find({kind, name});
  if (it == registered_.end())
    return makeError(ErrorCode::NotFound, std::string("unknown ") + assetKindName(kind) + " '" + name + "'");
  return it->second;
}

template <class Gpu, class MakeBuiltin, class Decode, class Upload>
Result<std::shared_ptr<const Gpu>> RendererImpl::findOrLoad(AssetKind kind, const std::string& name,
                                                            const std::string& key,
                                                            std::map<std::string, std::shared_ptr<const Gpu>>& builtins,
                                                            std::map<std::string, std::weak_ptr<const Gpu>>& uploads,
                                                            MakeBuiltin makeBuiltin, Decode decode, Upload upload) {
  if (auto it = builtins.find(key); it != builtins.end()) return it->second;
  if (auto cached = lockCached(uploads, key)) return cached;
  const std::string what = std::string("the ") + assetKindName(kind) + " '" + name + "'";
  // Reserves what the asset will hold on the device, and for the upload's length its decoded
  // data and staging buffers, then uploads it.
  auto place = [&](const auto& data) -> Result<std::shared_ptr<Gpu>> {
    const uint64_t resident = deviceBytes(data);
    BRDFA_TRY(ledger_->reserve(MemoryUse::Transfers, hostBytes(data) + resident, what, shrinker({.assets = true})));
    MemoryReservation transfer(ledger_.get(), MemoryUse::Transfers, hostBytes(data) + resident);
    BRDFA_TRY(ledger_->reserve(MemoryUse::Assets, resident, what, shrinker({.assets = true})));
    MemoryReservation memory(ledger_.get(), MemoryUse::Assets, resident);
    auto gpu = upload(data);
    if (!gpu) return gpu.takeError();
    (*gpu)->memory = std::move(memory);
    return gpu;
  };
  if (auto builtin = makeBuiltin()) {
    auto gpu = place(*builtin);
    if (!gpu) return gpu.takeError();
    builtins[key] = gpu.value();
    return std::shared_ptr<const Gpu>(gpu.value());
  }
  auto path = registeredPath(kind, name);
  if (!path) return path.takeError();
  auto bytes = readWholeFile(*path);
  if (!bytes) return assetError(bytes.takeError(), kind, name);
  // The file and what it decodes to are in flight until the upload ends.
  BRDFA_TRY(ledger_->reserve(MemoryUse::Transfers, bytes->size(), what, shrinker({.assets = true})));
  MemoryReservation file(ledger_.get(), MemoryUse::Transfers, bytes->size());
  auto data = decode(std::string_view(*bytes));
  if (!data) return assetError(data.takeError(), kind, name);
  auto gpu = place(*data);
  if (!gpu) return gpu.takeError();
  uploads[key] = gpu.value();
  return std::shared_ptr<const Gpu>(gpu.value());
}

Result<std::shared_ptr<GpuEnvironment>> RendererImpl::uploadEnvironment(const std::string& name,
                                                                       const EnvironmentData& data) {
  ImageSpec spec;
  spec.width = spec.height = data.faceSize;
  spec.layers = 6;
  spec.cube = true;
  spec.format = VK_FORMAT_R16G16B16A16_SFLOAT;  // linear filtering is guaranteed for 16F, not 32F
  spec.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  auto image = Image::create(*ctx_, spec);
  if (!image) return image.takeError();
  const HalfCube half = packHalfCube(data);
  BRDFA_TRY(uploadImage(*ctx_, *image, half.texels.data(), half.texels.size() * sizeof(uint16_t)));
  std::shared_ptr<const EnvironmentDistribution> distribution;
  if (!data.constant) {
    // The table is a texel buffer, and Vulkan only promises 65536 texels in one: a device at that
    // minimum gets coarser cells (6 D^2 + 1 entries and the preview's must fit).
    uint32_t maxCells = kMaxCellsPerEdge;
    while (maxCells > 1 && 6ull * maxCells * maxCells + 1 + kPreviewEntries > ctx_->limits().maxTexelBufferElements)
      maxCells /= 2;
    distribution = std::make_shared<const EnvironmentDistribution>(buildEnvironmentDistribution(data, maxCells));
  }
  std::vector<uint32_t> table = distribution ? distribution->table : EnvironmentDistribution::constantHeader();
  if (distribution) {  // the preview kernel's coarse radiance after the cells (environment_preview.h)
    const std::vector<uint32_t> preview = previewRadianceEntries(data, half.scale);
    table.insert(table.end(), preview.begin(), preview.end());
  }
  auto tableBuffer = TexelBuffer::create(*ctx_, table.data(), table.size() * sizeof(uint32_t), VK_FORMAT_R32G32_UINT);
  if (!tableBuffer) return tableBuffer.takeError();
  auto env = std::make_shared<GpuEnvironment>();
  env->name = name;
  env->constant = data.constant;
  env->scale = half.scale;
  env->cube = std::move(image.value());
  env->table = std::move(tableBuffer.value());
  env->distribution = std::move(distribution);
  return env;
}

Result<std::shared_ptr<const GpuEnvironment>> RendererImpl::environment(const std::string& name) {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return findOrLoad(
      AssetKind::Environment, name, name, environments_, uploadedEnvironments_,
      [&] { return makeBuiltinEnvironment(name); },
      [&](std::string_view bytes) { return decodeEnvironment(bytes, kUnlimited, name, nullptr); },
      [&](const EnvironmentData& data) { return uploadEnvironment(name, data); });
}

Result<std::shared_ptr<GpuMesh>> RendererImpl::uploadMesh(const std::string& name, const MeshData& data) {
  if (data.vertices.empty() || data.indices.empty())
    return makeError(ErrorCode::InvalidArgument, "mesh '" + name + "' has no triangles");
  auto gpu = std::make_shared<GpuMesh>();
  gpu->name = name;
  gpu->vertexCount = static_cast<uint32_t>(data.vertices.size());
  for (int a = 0; a < 3; ++a) {
    gpu->boundsMin[a] = INFINITY;
    gpu->boundsMax[a] = -INFINITY;
  }
  for (const Vertex& v : data.vertices)
    for (int a = 0; a < 3; ++a) {
      gpu->boundsMin[a] = std::min(gpu->boundsMin[a], v.position[a]);
      gpu->boundsMax[a] = std::max(gpu->boundsMax[a], v.position[a]);
    }
  gpu->indexCount = static_cast<uint32_t>(data.indices.size());
  auto vb = deviceBufferWith(*ctx_, data.vertices.data(), data.vertices.size() * sizeof(Vertex),
                             VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  if (!vb) return vb.takeError();
  auto ib = deviceBufferWith(*ctx_, data.indices.data(), data.indices.size() * sizeof(uint32_t),
                             VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
  if (!ib) return ib.takeError();
  gpu->vertices = std::move(vb.value());
  gpu->indices = std::move(ib.value());
  return gpu;
}

Result<std::shared_ptr<const GpuMesh>> RendererImpl::mesh(const std::string& name) {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return findOrLoad(
      AssetKind::Mesh, name, name, meshes_, uploadedMeshes_, [&] { return makeBuiltinMesh(name); },
      [&](std::string_view bytes) { return loadObjMesh(bytes, kUnlimited, nullptr); },
      [&](const MeshData& data) { return uploadMesh(name, data); });
}

Result<std::shared_ptr<GpuTexture>> RendererImpl::uploadTexture(const std::string& name, bool srgb,
                                                               const TextureData& data) {
  if (data.width == 0 || data.height == 0 || data.rgba8.size() != size_t(data.width) * data.height * 4)
    return makeError(ErrorCode::InvalidArgument, "texture '" + name + "' has no pixels");
  ImageSpec spec;
  spec.width = data.width;
  spec.height = data.height;
  // The sampler decodes sRGB to linear (before filtering, as it should be).
  spec.format = srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM;
  spec.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  auto image = Image::create(*ctx_, spec);
  if (!image) return image.takeError();
  BRDFA_TRY(uploadImage(*ctx_, *image, data.rgba8.data(), data.rgba8.size()));
  auto texture = std::make_shared<GpuTexture>();
  texture->name = name;
  texture->srgb = srgb;
  texture->image = std::move(image.value());
  return texture;
}

Result<std::shared_ptr<const GpuTexture>> RendererImpl::texture(const std::string& name, bool srgb) {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return findOrLoad(
      AssetKind::Texture, name, name + (srgb ? "|srgb" : "|linear"), textures_, uploadedTextures_,
      [&] { return makeBuiltinTexture(name); },
      [&](std::string_view bytes) { return decodeTexture(bytes, kUnlimited); },
      [&](const TextureData& data) { return uploadTexture(name, srgb, data); });
}

RendererCounters RendererImpl::counters() const {
  RendererCounters c;
  c.glslCompiles = glslCompiles_.load();
  c.glslCompileErrors = glslCompileErrors_.load();
  c.compileTime = compileTime_.snapshot();
  c.spirvCacheHits = spirvCacheHits_.load();
  c.spirvDiskHits = spirvDiskHits_.load();
  c.pipelinesCreated = pipelinesCreated_.load();
  c.memory = ledger_->usage();
  return c;
}

Result<void> RendererImpl::exchangeViewMemory(uint64_t oldBytes, uint64_t newBytes, const std::string& what,
                                              std::string* dropped) {
  return ledger_->exchange(MemoryUse::RenderTargets, oldBytes, newBytes, what, shrinker({}), dropped);
}

namespace {
// Erases entries of `cache` (oldest first, in `order`) that nothing but the cache holds, until
// `freed` reaches `needed`; counts them in `count`.
template <class Map>
void dropUnused(Map& cache, std::deque<uint64_t>& order, uint64_t needed, uint64_t& freed, int& count,
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

template <class Gpu>
void dropUnusedAssets(std::map<std::string, std::shared_ptr<const Gpu>>& cache, uint64_t needed, uint64_t& freed,
                      std::vector<std::string>& names) {
  for (auto it = cache.begin(); it != cache.end() && freed < needed;) {
    if (it->second.use_count() == 1) {
      freed += it->second->memory.bytes();
      names.push_back(it->second->name);
      it = cache.erase(it);
    } else {
      ++it;
    }
  }
}
}  // namespace

std::string RendererImpl::dropUnusedCaches(uint64_t needed, HeldLocks held) {
  uint64_t freed = 0;
  int programs = 0, spirv = 0;
  std::vector<std::string> assets;
  // A lock this thread does not hold is taken only if it is free: a shrink never waits.
  auto withLock = [](std::mutex& m, bool heldByCaller, auto&& body) {
    if (heldByCaller) return body();
    std::unique_lock lock(m, std::try_to_lock);
    if (lock.owns_lock()) body();
  };
  withLock(kernelMutex_, held.kernels, [&] {
    dropUnused(kernelCache_, kernelOrder_, needed, freed, programs,
               [&](uint64_t key) { return kernelCache_.at(key)->memory.bytes(); });
  });
  withLock(spirvMutex_, false, [&] {
    dropUnused(spirvCache_, spirvOrder_, needed, freed, spirv, [&](uint64_t key) {
      const uint64_t bytes = spirvMemory_[key].bytes();
      spirvMemory_.erase(key);
      return bytes;
    });
  });
  withLock(assetMutex_, held.assets, [&] {
    dropUnusedAssets(environments_, needed, freed, assets);
    dropUnusedAssets(meshes_, needed, freed, assets);
    dropUnusedAssets(textures_, needed, freed, assets);
  });
  if (freed == 0) return {};
  std::string what;
  auto add = [&](const std::string& part) { what += (what.empty() ? "" : ", ") + part; };
  if (programs) add(std::to_string(programs) + " cached program" + (programs == 1 ? "" : "s"));
  if (spirv) add(std::to_string(spirv) + " cached SPIR-V module" + (spirv == 1 ? "" : "s"));
  for (const std::string& name : assets) add("the unused asset '" + name + "'");
  what = "dropped " + what + " (" + mebibytesText(freed) + ") to stay within the memory budget; they are rebuilt when used";
  ledger_->noteDropped(freed, what);
  return what;
}

namespace {
std::vector<std::string> withRegistered(std::vector<std::string> names,
                                        const std::map<std::pair<AssetKind, std::string>, std::string>& registered,
                                        AssetKind kind) {
  for (const auto& [key, path] : registered)  // sorted by (kind, name)
    if (key.first == kind) names.push_back(key.second);
  return names;
}
}  // namespace

std::vector<std::string> RendererImpl::environmentNames() const {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return withRegistered(builtinEnvironmentNames(), registered_, AssetKind::Environment);
}

std::vector<std::string> RendererImpl::meshNames() const {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return withRegistered(builtinMeshNames(), registered_, AssetKind::Mesh);
}

std::vector<std::string> RendererImpl::textureNames() const {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return withRegistered(builtinTextureNames(), registered_, AssetKind::Texture);
}

Result<std::unique_ptr<RenderView>> RendererImpl::createView() {
  auto view = std::make_unique<RenderViewImpl>(shared_from_this());
  BRDFA_TRY(view->init());
  return std::unique_ptr<RenderView>(std::move(view));
}

}  // namespace brdfa
