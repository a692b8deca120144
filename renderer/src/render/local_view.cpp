#include "render/local_view.h"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numeric>

#include "core/scene_check.h"
#include "core/scene_math.h"
#include "device/vk_check.h"
#include "render/host_resolve.h"

namespace brdfa {

namespace {

constexpr uint32_t kShadeGroup = 8;  // local size of shade/background kernels
// The preview scratch holds at most this many 2x2 blocks: a scratch for a whole image in every
// view costs a class of many views much memory; a larger object's preview goes in several
// dispatches instead, which cost little more time.
constexpr uint32_t kPreviewScratchBlocks = 16384;
constexpr VkDeviceSize kPreviewScratchBlockBytes = 6 * 16;  // BRDFA_PREVIEW_STRIDE texels
constexpr uint32_t kResolveGroup = 16;                      // local size of the resolve kernel
constexpr double kErrorRefreshMs = 200;  // rel_error is refreshed at least this often while rendering
// The passes right after the first one of a restart are what the next change of a user moving a
// slider or the camera meets: each is split into at least SubmissionSizer::kInteractiveSplits
// submissions, so that interruptPass() takes effect within a fraction of it. By the pass's cost
// units, not by time: a unit's time differs several-fold between 1 and 16 samples a pass (the
// kernel's per-pixel part, run for every dispatched pixel), and sized by a time target an
// interactive pass went in many more submissions. The first pass, whose frame the user waits
// for, and later ones use the device's target alone: every submission waits for the slowest of
// a CPU device's threads, and a pass in several submissions takes longer than in one.
constexpr uint64_t kInteractivePasses = 3;
// A restart of `render` begins with a preview pass (RenderSettings::previewPass).
bool wantsPreview(const RenderSettings& render) {
  return render.previewPass && uint64_t(render.width) * render.height >= RenderSettings::kPreviewMinPixels;
}

// A program not yet run may want the preview kernel: for a preview, or a first sample.
bool wantsPreviewKernel(const RenderSettings& render) { return wantsPreview(render) || render.firstSampleKernel; }

uint32_t groups(uint32_t n, uint32_t size) { return (n + size - 1) / size; }

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

bool sameVec(const Vec3& a, const Vec3& b) { return a == b; }

bool sameGeometry(const Scene& a, const Scene& b) {
  const Camera &ca = a.camera, &cb = b.camera;
  if (!sameVec(ca.position, cb.position) || ca.yaw != cb.yaw || ca.pitch != cb.pitch || ca.fov != cb.fov) return false;
  if (a.objects.size() != b.objects.size()) return false;
  for (size_t i = 0; i < a.objects.size(); ++i) {
    const SceneObject &oa = a.objects[i], &ob = b.objects[i];
    if (oa.mesh != ob.mesh || !sameVec(oa.translate, ob.translate) || !sameVec(oa.rotate, ob.rotate) ||
        !sameVec(oa.scale, ob.scale))
      return false;
  }
  return true;
}

bool sameLighting(const Scene& a, const Scene& b) {
  const EnvironmentSettings &ea = a.environment, &eb = b.environment;
  return ea.name == eb.name && ea.intensity == eb.intensity && ea.rotation == eb.rotation && ea.visible == eb.visible &&
         a.render.sampling == b.render.sampling && a.render.seed == b.render.seed;
}

}  // namespace

LocalView::LocalView(std::shared_ptr<LocalRenderer> renderer) : r_(std::move(renderer)) {}

LocalView::~LocalView() {
  (void)r_->exchangeViewMemory(reservedBytes_, 0, "");  // giving back never fails
  VkDevice d = r_->ctx().device();
  releaseObjects(objects_);
  if (framebuffer_) vkDestroyFramebuffer(d, framebuffer_, nullptr);
  if (pool_) vkDestroyDescriptorPool(d, pool_, nullptr);
}

Result<void> LocalView::init() {
  VkContext& ctx = r_->ctx();
  auto cmd = CommandContext::create(ctx);
  if (!cmd) return cmd.takeError();
  cmd_ = std::move(cmd.value());

  // New objects are built before the old ones are released, hence room for two scenes' worth.
  VkDescriptorPoolSize sizes[4] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 7 * kMaxJitter + 2 * kMaxObjects},
                                   {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, kMaxJitter + 8 * kMaxObjects},
                                   {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 4 * kMaxObjects},
                                   {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 4 * kMaxJitter}};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  pci.maxSets = kMaxJitter + 2 * kMaxObjects;
  pci.poolSizeCount = 4;
  pci.pPoolSizes = sizes;
  BRDFA_VK_TRY(vkCreateDescriptorPool(ctx.device(), &pci, nullptr, &pool_));
  VkDescriptorSetLayout layouts[kMaxJitter];
  for (VkDescriptorSetLayout& l : layouts) l = r_->viewSetLayout();
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = pool_;
  ai.descriptorSetCount = kMaxJitter;
  ai.pSetLayouts = layouts;
  BRDFA_VK_TRY(vkAllocateDescriptorSets(ctx.device(), &ai, viewSets_));

  auto counters = Buffer::create(ctx, 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
  if (!counters) return counters.takeError();
  counters_ = std::move(counters.value());
  return {};
}

// Shaders below SPIR-V 1.6 run with gl_SubgroupSize equal to the device's subgroupSize property
// (no varying sizes), so each workgroup writes exactly this many partial sums.
size_t LocalView::partialCount(uint32_t width, uint32_t height) const {
  const uint32_t perGroup = (kResolveGroup * kResolveGroup + r_->ctx().subgroupSize() - 1) / r_->ctx().subgroupSize();
  return size_t(groups(width, kResolveGroup)) * groups(height, kResolveGroup) * perGroup;
}

Result<void> LocalView::resize(uint32_t width, uint32_t height) {
  VkContext& ctx = r_->ctx();
  // Everything below, counted against the renderer's budget before any of it is allocated.
  const VkDeviceSize pixels = VkDeviceSize(width) * height;
  const uint32_t jitter = pixels <= VkDeviceSize(1024) * 1024 ? kMaxJitter : 1;
  // Slices and planes start where both a storage-buffer range and a texel view may start.
  const VkDeviceSize align = std::max<VkDeviceSize>(
      {ctx.limits().minStorageBufferOffsetAlignment, ctx.limits().minTexelBufferOffsetAlignment, 16});
  auto aligned = [&](VkDeviceSize n) { return (n + align - 1) / align * align; };
  // Texel views address at most maxTexelBufferElements texels (2^27 on lavapipe, more on GPUs).
  // The largest views now hold one texel per pixel (a G-buffer plane, the edge list); the bound
  // stays at the accumulators' two halves, from when they were a texel view too.
  if (2 * pixels > ctx.limits().maxTexelBufferElements)
    return makeError(ErrorCode::InvalidArgument, "a " + std::to_string(width) + "x" + std::to_string(height) +
                                                     " view is more than this device's texel buffers can address");
  const VkDeviceSize detailOffset = aligned(pixels * kGbufferSurfaceBytes);
  // A preview-kernel dispatch needs one scratch block per invocation: per 2x2 block in a
  // preview, per pixel in a first sample. At most kPreviewScratchBlocks, more only where one
  // row of the first sample's workgroups needs it (dispatches take whole rows while one fits).
  // Only a device that compiles at the first dispatch runs the preview kernel; elsewhere one
  // block keeps the binding valid.
  const uint32_t rowBlocks = groups(width, kShadeGroup) * kShadeGroup * kShadeGroup;
  const uint32_t scratchBlocks =
      !r_->compilesAtFirstDispatch()
          ? 1u
          : std::min<uint32_t>(std::max(kPreviewScratchBlocks, rowBlocks), groups(height, kShadeGroup) * rowBlocks);
  const VkDeviceSize stride = aligned(detailOffset + pixels * kGbufferDetailBytes);
  const uint64_t bytes = pixels * (kGbufferSurfaceBytes + kGbufferDetailBytes + 4)  // raster targets and depth
                         + stride * jitter + pixels * 32                            // G-buffer copies, accumulators
                         + pixels * (4 + 16) + partialCount(width, height) * 16     // outputs
                         + pixels * 4                                               // edge list
                         + scratchBlocks * kPreviewScratchBlockBytes;
  // The old size's share is given back in the same step: a refused size leaves the view as it
  // was, still rendering its old size.
  BRDFA_TRY(r_->exchangeViewMemory(reservedBytes_, bytes,
                                   "a " + std::to_string(width) + "x" + std::to_string(height) + " view"));
  reservedBytes_ = bytes;
  jitterCount_ = jitter;
  sliceStride_ = stride;
  detailOffset_ = detailOffset;
  BRDFA_TRY(createTargets(width, height));
  BRDFA_TRY(createBuffers(width, height, scratchBlocks));
  width_ = width;
  height_ = height;
  return {};
}

// Drops the old size's framebuffer and texel views (width_ and height_ read 0 until resize
// completes), and creates the raster targets and framebuffer of a width x height view.
Result<void> LocalView::createTargets(uint32_t width, uint32_t height) {
  VkContext& ctx = r_->ctx();
  VkDevice d = ctx.device();
  if (framebuffer_) vkDestroyFramebuffer(d, framebuffer_, nullptr);
  framebuffer_ = VK_NULL_HANDLE;
  width_ = height_ = 0;

  for (TexelView& v : surfaceViews_) v.reset();
  for (TexelView& v : detailViews_) v.reset();
  edgeView_.reset();
  edgeListKnown_ = false;
  ImageSpec g;
  g.width = width;
  g.height = height;
  g.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  for (auto [img, format] :
       {std::pair{&gSurface_, kGbufferSurfaceFormat}, std::pair{&gDetail_, kGbufferDetailFormat}}) {
    g.format = format;
    auto created = Image::create(ctx, g);
    if (!created) return created.takeError();
    *img = std::move(created.value());
  }
  ImageSpec dspec = g;
  dspec.format = VK_FORMAT_D32_SFLOAT;
  dspec.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
  dspec.aspect = VK_IMAGE_ASPECT_DEPTH_BIT;
  auto depth = Image::create(ctx, dspec);
  if (!depth) return depth.takeError();
  depth_ = std::move(depth.value());

  VkImageView views[3] = {gSurface_.view(), gDetail_.view(), depth_.view()};
  VkFramebufferCreateInfo fci{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
  fci.renderPass = r_->gbufferPass();
  fci.attachmentCount = 3;
  fci.pAttachments = views;
  fci.width = width;
  fci.height = height;
  fci.layers = 1;
  BRDFA_VK_TRY(vkCreateFramebuffer(d, &fci, nullptr, &framebuffer_));
  return {};
}

// Creates the view's buffers for a width x height view (sizes, slices and planes as resize set
// them, `scratchBlocks` preview scratch blocks) and their texel views.
Result<void> LocalView::createBuffers(uint32_t width, uint32_t height, uint32_t scratchBlocks) {
  VkContext& ctx = r_->ctx();
  const VkDeviceSize pixels = VkDeviceSize(width) * height;
  const VkBufferUsageFlags storage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  // Four jittered slices (jitterCount_ above) cost 4 x 24 bytes per pixel;
  // above 1024^2 pixels the memory is not worth it and the image is not anti-aliased (its
  // pixels are small anyway).
  slicesReady_ = 0;
  struct Want {
    Buffer* buffer;
    VkDeviceSize size;
    VkBufferUsageFlags usage;
    bool host;
  };
  // With the host resolve, the host reads the G-buffer and accumulators in place; on a CPU
  // device the host also lists the edge pixels from the G-buffer (listEdgePixels), whichever
  // resolve runs, so both resolves see the same image.
  const bool host = r_->hostResolve() || r_->ctx().info().type == "cpu";
  const Want wants[7] = {{&gbuffer_, sliceStride_ * jitterCount_,
                          storage | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, host},
                         {&accum_, pixels * 2 * 16, storage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, host},
                         {&outRgba8_, pixels * 4, storage, true},
                         {&outFloat_, pixels * 16, storage, true},
                         {&partials_, VkDeviceSize(partialCount(width, height)) * 16, storage, true},
                         {&edgeList_, pixels * 4, VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT, true},
                         {&previewScratch_, scratchBlocks * kPreviewScratchBlockBytes, storage, false}};
  for (const Want& w : wants) {
    auto b = Buffer::create(ctx, w.size, w.usage, w.host);
    if (!b) return b.takeError();
    *w.buffer = std::move(b.value());
  }
  for (uint32_t slice = 0; slice < jitterCount_; ++slice) {
    auto surface =
        TexelView::create(ctx, gbuffer_, kGbufferSurfaceFormat, sliceStride_ * slice, pixels * kGbufferSurfaceBytes);
    if (!surface) return surface.takeError();
    surfaceViews_[slice] = std::move(surface.value());
    auto detail = TexelView::create(ctx, gbuffer_, kGbufferDetailFormat, sliceStride_ * slice + detailOffset_,
                                    pixels * kGbufferDetailBytes);
    if (!detail) return detail.takeError();
    detailViews_[slice] = std::move(detail.value());
  }
  auto edgeView = TexelView::create(ctx, edgeList_, VK_FORMAT_R32_UINT, 0, VK_WHOLE_SIZE);
  if (!edgeView) return edgeView.takeError();
  edgeView_ = std::move(edgeView.value());
  previewScratchBlocks_ = scratchBlocks;
  return {};
}

void LocalView::writeViewDescriptors() {
  VkDescriptorImageInfo env{r_->environmentSampler(), env_->cube.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  const VkBufferView table = env_->table.view();
  const std::pair<uint32_t, const Buffer*> buffers[7] = {{0, &gbuffer_},        {3, &accum_},    {4, &counters_},
                                                         {6, &outRgba8_},       {7, &outFloat_}, {8, &partials_},
                                                         {12, &previewScratch_}};
  const VkDeviceSize sliceBytes = detailOffset_ + VkDeviceSize(width_) * height_ * kGbufferDetailBytes;
  // Every set is written (unused slices alias slice 0) so that no set is ever left invalid.
  for (uint32_t slice = 0; slice < kMaxJitter; ++slice) {
    const uint32_t s = slice < jitterCount_ ? slice : 0;
    VkDescriptorBufferInfo infos[7];
    VkWriteDescriptorSet w[12] = {};
    for (uint32_t i = 0; i < 12; ++i) {
      w[i].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
      w[i].dstSet = viewSets_[slice];
      w[i].descriptorCount = 1;
    }
    for (uint32_t i = 0; i < 7; ++i) {
      infos[i] = {buffers[i].second->handle(), 0, VK_WHOLE_SIZE};
      w[i].dstBinding = buffers[i].first;
      w[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      w[i].pBufferInfo = &infos[i];
    }
    infos[0].offset = s * sliceStride_;
    infos[0].range = sliceBytes;
    w[7].dstBinding = 5;
    w[7].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w[7].pImageInfo = &env;
    const std::pair<uint32_t, VkBufferView> texels[4] = {
        {9, table}, {10, surfaceViews_[s].view()}, {11, detailViews_[s].view()}, {13, edgeView_.view()}};
    for (uint32_t i = 0; i < 4; ++i) {
      w[8 + i].dstBinding = texels[i].first;
      w[8 + i].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
      w[8 + i].pTexelBufferView = &texels[i].second;
    }
    vkUpdateDescriptorSets(r_->ctx().device(), 12, w, 0, nullptr);
  }
}

void LocalView::releaseObjects(std::vector<ObjectState>& objects) {
  for (ObjectState& o : objects)
    if (o.set) vkFreeDescriptorSets(r_->ctx().device(), pool_, 1, &o.set);
  objects.clear();
}

std::vector<std::optional<LocalRenderer::ShadeKernels>> LocalView::prebuildKernels(const Scene& scene) {
  std::vector<std::optional<LocalRenderer::ShadeKernels>> built(scene.objects.size());
  auto env = r_->environment(scene.environment.name);
  if (!env) return built;  // setScene reports it
  const bool constantEnv = (*env)->constant;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& so = scene.objects[i];
    auto kernels = r_->shadeKernels(*so.brdf, shadeVariant(*so.brdf, scene.render.sampling, constantEnv), constantEnv,
                                    wantsPreviewKernel(scene.render));
    if (kernels) built[i] = kernels.value();  // else buildObjects asks again and reports it
  }
  return built;
}

Result<std::vector<LocalView::ObjectState>> LocalView::buildObjects(
    const Scene& scene, const std::vector<std::optional<LocalRenderer::ShadeKernels>>& prebuilt) {
  VkContext& ctx = r_->ctx();
  const bool constantEnv = env_ && env_->constant;
  std::vector<ObjectState> out;
  auto fail = [&](Error e) -> Result<std::vector<ObjectState>> {
    releaseObjects(out);
    return e;
  };
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& so = scene.objects[i];
    const std::string at = "objects[" + std::to_string(i) + "]";
    ObjectState o;
    o.variant = shadeVariant(*so.brdf, scene.render.sampling, constantEnv);
    // A program not yet run on a device that compiles it at its first dispatch (lavapipe; a mis
    // program's compile is long) previews by the preview kernel, whose own compile is a
    // fraction of that, and compiles in the first pass.
    auto kernels = i < prebuilt.size() && prebuilt[i]
                       ? Result<LocalRenderer::ShadeKernels>(*prebuilt[i])
                       : r_->shadeKernels(*so.brdf, o.variant, constantEnv, wantsPreviewKernel(scene.render));
    if (!kernels) {
      Error e = kernels.takeError();
      if (e.field.empty()) e.field = at + ".brdf";
      return fail(std::move(e));
    }
    o.kernel = kernels->kernel;
    o.previewKernel = kernels->preview;
    auto mesh = r_->mesh(so.mesh);
    if (!mesh) {
      Error e = mesh.takeError();
      e.field = at + ".mesh";
      return fail(std::move(e));
    }
    o.mesh = mesh.value();
    if (!so.brdf->measuredTable.empty()) {
      auto table = r_->measured(so.brdf->measuredTable);
      if (!table) {
        Error e = table.takeError();
        e.field = at + ".brdf";
        return fail(std::move(e));
      }
      o.measured = table.value();
    }
    for (size_t t = 0; t < so.textures.size() && t < static_cast<size_t>(kMaxTextures); ++t) {
      auto texture = r_->texture(so.textures[t].name, so.textures[t].srgb);
      if (!texture) {
        Error e = texture.takeError();
        e.field = at + ".textures[" + std::to_string(t) + "]";
        return fail(std::move(e));
      }
      o.textures[t] = texture.value();
    }

    std::vector<uint8_t> packed = o.kernel->params.pack(*so.brdf, so.params);
    auto params = Buffer::create(ctx, packed.size(), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true);
    if (!params) return fail(params.takeError());
    std::memcpy(params->mapped(), packed.data(), packed.size());
    o.params = std::move(params.value());

    ObjectUniform u{};
    glm::mat4 model = modelMatrix(so);
    glm::mat4 normal = glm::transpose(glm::inverse(model));
    std::memcpy(u.model, glm::value_ptr(model), sizeof(u.model));
    std::memcpy(u.normalMatrix, glm::value_ptr(normal), sizeof(u.normalMatrix));
    u.id[0] = static_cast<float>(i + 1);
    auto transform = Buffer::create(ctx, sizeof(u), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true);
    if (!transform) return fail(transform.takeError());
    std::memcpy(transform->mapped(), &u, sizeof(u));
    o.transform = std::move(transform.value());

    VkDescriptorSetLayout layout = r_->objectSetLayout();
    VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    ai.descriptorPool = pool_;
    ai.descriptorSetCount = 1;
    ai.pSetLayouts = &layout;
    VkResult vr = vkAllocateDescriptorSets(ctx.device(), &ai, &o.set);
    if (vr != VK_SUCCESS) return fail(vkError(vr, "vkAllocateDescriptorSets"));
    VkDescriptorBufferInfo infos[2] = {{o.params.handle(), 0, VK_WHOLE_SIZE}, {o.transform.handle(), 0, VK_WHOLE_SIZE}};
    VkWriteDescriptorSet w[2] = {};
    for (uint32_t b = 0; b < 2; ++b) {
      w[b].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
      w[b].dstSet = o.set;
      w[b].dstBinding = b;
      w[b].descriptorCount = 1;
      w[b].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
      w[b].pBufferInfo = &infos[b];
    }
    vkUpdateDescriptorSets(ctx.device(), 2, w, 0, nullptr);
    r_->writeTextures(o.set, o.textures);
    r_->writeMeasured(o.set, o.measured.get());
    out.push_back(std::move(o));
  }
  return out;
}

void LocalView::interruptPass() { interruptRequested_ = true; }

Result<void> LocalView::setScene(const Scene& scene) {
  BRDFA_TRY(checkScene(scene));
  // The programs are built (glslang, pipeline) before the view is taken: a pass in flight goes
  // on meanwhile, to the end of its submission (interruptPass), so a change waits for the
  // longer of the two instead of both.
  const std::vector<std::optional<LocalRenderer::ShadeKernels>> prebuilt = prebuildKernels(scene);
  std::lock_guard<std::mutex> lock(mutex_);
  interruptRequested_ = false;  // served: this call has the view now
  const uint64_t dropsBefore = r_->memoryUsage().drops;
  auto env = r_->environment(scene.environment.name);
  if (!env) {
    Error e = env.takeError();
    e.field = "environment.name";
    return e;
  }
  auto previousEnv = env_;
  env_ = env.value();  // buildObjects specializes kernels to the environment kind
  auto built = buildObjects(scene, prebuilt);
  if (!built) {
    env_ = previousEnv;
    return built.takeError();
  }
  std::vector<ObjectState> objects = std::move(built.value());

  const auto width = static_cast<uint32_t>(scene.render.width);
  const auto height = static_cast<uint32_t>(scene.render.height);
  const bool resized = !hasScene_ || width != width_ || height != height_;
  if (resized) {
    auto r = resize(width, height);
    if (!r) {
      releaseObjects(objects);
      if (r.error().code == ErrorCode::OverBudget) {
        env_ = previousEnv;  // refused before anything changed: the old scene goes on
        return r.takeError();
      }
      hasScene_ = false;  // size-dependent resources are gone; the next setScene rebuilds them
      return r.takeError();
    }
  }
  if (resized || previousEnv != env_) writeViewDescriptors();

  const SceneChange change = compareScene(scene, objects, resized);
  adoptScene(scene, std::move(objects), change);
  describeScene(dropsBefore);
  updateDone();
  return {};
}

// How `scene`, with `objects` built for it, differs from the scene the view holds (any scene
// differs in everything from none). `resized`: the new scene's size differs.
LocalView::SceneChange LocalView::compareScene(const Scene& scene, const std::vector<ObjectState>& objects,
                                               bool resized) const {
  SceneChange c;
  c.sameShading = hasScene_ && !resized && sameLighting(scene_, scene) && objects.size() == objects_.size();
  for (size_t i = 0; c.sameShading && i < objects.size(); ++i) {
    c.sameShading =
        objects[i].kernel->programHash == objects_[i].kernel->programHash &&
        objects[i].params.size() == objects_[i].params.size() &&
        std::memcmp(objects[i].params.mapped(), objects_[i].params.mapped(), objects[i].params.size()) == 0 &&
        scene.objects[i].textures == scene_.objects[i].textures;
  }
  // The same pipelines (parameters, textures or lighting changed): no driver compile comes with
  // the next dispatch.
  c.samePrograms = hasScene_ && objects.size() == objects_.size();
  for (size_t i = 0; c.samePrograms && i < objects.size(); ++i)
    c.samePrograms = objects[i].kernel->programHash == objects_[i].kernel->programHash;
  c.geometryChanged = resized || !hasScene_ || !sameGeometry(scene_, scene);
  c.lightingChanged = !hasScene_ || !sameLighting(scene_, scene);
  c.restart = c.geometryChanged || !c.sameShading;
  c.displayChanged =
      !hasScene_ || scene.render.exposure != scene_.render.exposure || scene.render.toneMap != scene_.render.toneMap ||
      scene.render.samplesPerFrame != scene_.render.samplesPerFrame ||
      scene.render.maxSamples != scene_.render.maxSamples || scene.render.targetError != scene_.render.targetError;
  return c;
}

// Makes `scene` with its `objects` the view's: their screen bounds and coverage, what must be
// redrawn (G-buffer slices, edge list, clears), what the submission sizer relearns, and on a
// restart the pass state and statistics started again (sceneVersion goes on).
void LocalView::adoptScene(const Scene& scene, std::vector<ObjectState> objects, const SceneChange& change) {
  const auto width = static_cast<uint32_t>(scene.render.width);
  const auto height = static_cast<uint32_t>(scene.render.height);
  const glm::mat4 viewProj = cameraFrame(scene.camera, width, height).viewProj;
  for (size_t i = 0; i < objects.size(); ++i)
    objects[i].pixels = screenBounds(viewProj, modelMatrix(scene.objects[i]), objects[i].mesh->boundsMin,
                                     objects[i].mesh->boundsMax, width, height);
  if (change.geometryChanged)
    coverageKnown_ = false;
  else  // the coverage depends on the geometry only
    for (size_t i = 0; i < objects.size(); ++i) objects[i].cover = std::move(objects_[i].cover);
  releaseObjects(objects_);
  objects_ = std::move(objects);
  scene_ = scene;
  hasScene_ = true;
  if (change.geometryChanged) {
    slicesReady_ = 0;
    edgeListKnown_ = false;
  }
  coverRect_ = PixelRect{};
  for (const ObjectState& o : objects_) coverRect_ = unionRect(coverRect_, o.pixels);
  // A new camera, geometry or environment changes coverage or background: clear everything and
  // redraw the background. A new BRDF or parameters keep both: the first pass overwrites the
  // object pixels instead (see the shade kernel), which is cheaper.
  if (change.geometryChanged || change.lightingChanged) clearPending_ = true;
  // What a submission costs is relearned when what the shading runs changed (a parameter can
  // be a loop count), by a probe; a camera move keeps it. With the same pipelines the probe
  // carries no driver compile (no warm-up), and the largest submission so far still bounds the
  // growth after it: a slider's change costs a probe and the pass, not a ramp of submissions
  // (each with its wake-ups, which cost a loaded CPU much of a frame).
  if (!change.sameShading) submissionSizer_.shadingChanged(change.samePrograms);
  if (change.restart) {
    partial_.reset();  // its samples are of the old image
    sizer_.reset();    // the costs of what is drawn now are unmeasured
    firstSamplePending_ = false;
    for (const ObjectState& o : objects_)
      firstSamplePending_ |= scene.render.firstSampleKernel && o.previewKernel && !o.kernel->dispatched;
    previewPending_ = wantsPreview(scene.render) && !firstSamplePending_;  // a first sample shows sooner
    const uint64_t version = stats_.sceneVersion;
    stats_ = FrameStats{};
    stats_.sceneVersion = version;
    sinceErrorMs_ = 0;
  }
  if (change.restart || change.displayChanged) ++stats_.sceneVersion;
}

// The statistics that describe the scene rather than its passes: geometry and program sizes,
// estimators and warnings, and a warning where optional caches were dropped since `dropsBefore`.
void LocalView::describeScene(uint64_t dropsBefore) {
  stats_.vertices = stats_.triangles = stats_.programBytes = 0;
  stats_.estimator.clear();
  stats_.warnings.clear();
  // Optional caches dropped to make room for this scene: said where the user looks.
  if (const MemoryUsage memory = r_->memoryUsage(); memory.drops != dropsBefore)
    stats_.warnings.push_back("memory: " + memory.lastDropped);
  std::vector<std::string> estimators;  // distinct, in object order
  for (size_t i = 0; i < objects_.size(); ++i) {
    const ShadeVariant& v = objects_[i].variant;
    if (std::find(estimators.begin(), estimators.end(), v.estimator) == estimators.end()) {
      estimators.push_back(v.estimator);
      stats_.estimator += (stats_.estimator.empty() ? "" : ", ") + v.estimator;
    }
    const std::string& brdfName = scene_.objects[i].brdfName;
    for (const std::string& w : v.warnings) {
      std::string named = brdfName.empty() ? w : brdfName + ": " + w;
      if (std::find(stats_.warnings.begin(), stats_.warnings.end(), named) == stats_.warnings.end())
        stats_.warnings.push_back(std::move(named));
    }
  }
  std::vector<uint64_t> programs;
  for (const ObjectState& o : objects_) {
    stats_.vertices += o.mesh->vertexCount;
    stats_.triangles += o.mesh->indexCount / 3;
    if (std::find(programs.begin(), programs.end(), o.kernel->programHash) != programs.end()) continue;
    programs.push_back(o.kernel->programHash);
    stats_.programBytes += o.kernel->spirvBytes;
  }
}

void LocalView::updateDone() {
  // A provisional sample is replaced by the next pass, which must run.
  stats_.maxSamplesReached = !stats_.provisional && stats_.spp >= static_cast<uint64_t>(scene_.render.maxSamples);
  // Below kMinSppForTarget the estimate rests on too few samples per half: a rare bright
  // direction (the sun) that neither half has met yet would read as no error at all.
  const double target = scene_.render.targetError;
  stats_.converged = target > 0 && stats_.spp >= kMinSppForTarget && stats_.relError && *stats_.relError <= target;
}

ComputePush LocalView::basePush() const {
  ComputePush p{};
  CameraFrame cam = cameraFrame(scene_.camera, width_, height_);
  auto put = [](float* dst, const glm::vec3& v) {
    dst[0] = v.x;
    dst[1] = v.y;
    dst[2] = v.z;
    dst[3] = 0;
  };
  put(p.cameraPos, cam.position);
  put(p.cameraRight, cam.right * (cam.tanHalfFov * cam.aspect));
  put(p.cameraUp, cam.up * cam.tanHalfFov);
  put(p.cameraForward, cam.forward);
  float rot = glm::radians(scene_.environment.rotation);
  p.env[0] = scene_.environment.intensity * (env_ ? env_->scale : 1.0f);
  p.env[1] = std::cos(rot);
  p.env[2] = std::sin(rot);
  p.frame[0] = width_;
  p.frame[1] = height_;
  p.target[1] = scene_.render.seed;
  p.tone[0] = std::exp2(scene_.render.exposure);
  p.tone[1] = static_cast<float>(static_cast<int>(scene_.render.toneMap));  // 0 clamp, 1 reinhard, 2 aces
  return p;
}

uint32_t LocalView::sliceForPass(uint64_t pass) const {
  // Every pass shares its samples between the half accumulators, so both halves see each slice
  // equally often (to within a sample). Even passes take slices 0, 1, 2, 3, odd ones 2, 3, 0, 1:
  // the first four passes touch all four slices, and every eight passes take each twice.
  const uint64_t j = jitterCount_;
  return static_cast<uint32_t>(((pass >> 1) + (pass & 1) * (j / 2)) % j);
}

void LocalView::recordRaster(VkCommandBuffer cb, uint32_t slice) {
  VkClearValue clears[3] = {};  // surface 0: background
  clears[2].depthStencil = {1.0f, 0};
  VkRenderPassBeginInfo rbi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  rbi.renderPass = r_->gbufferPass();
  rbi.framebuffer = framebuffer_;
  rbi.renderArea = {{0, 0}, {width_, height_}};
  rbi.clearValueCount = 3;
  rbi.pClearValues = clears;
  vkCmdBeginRenderPass(cb, &rbi, VK_SUBPASS_CONTENTS_INLINE);
  VkViewport vp{0, 0, static_cast<float>(width_), static_cast<float>(height_), 0, 1};
  VkRect2D scissor{{0, 0}, {width_, height_}};
  vkCmdSetViewport(cb, 0, 1, &vp);
  vkCmdSetScissor(cb, 0, 1, &scissor);
  vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, r_->gbufferPipeline());
  // Moving the geometry by -offset samples it at pixel centre + offset (the background kernel
  // looks through the same point).
  glm::mat4 viewProj = jitteredViewProj(cameraFrame(scene_.camera, width_, height_).viewProj,
                                        -jitterOffset(slice, jitterCount_), width_, height_);
  vkCmdPushConstants(cb, r_->rasterLayout(), VK_SHADER_STAGE_VERTEX_BIT, 0, 64, glm::value_ptr(viewProj));
  for (const ObjectState& o : objects_) {
    vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, r_->rasterLayout(), 1, 1, &o.set, 0, nullptr);
    VkBuffer vb = o.mesh->vertices.handle();
    VkDeviceSize offset = 0;
    vkCmdBindVertexBuffers(cb, 0, 1, &vb, &offset);
    vkCmdBindIndexBuffer(cb, o.mesh->indices.handle(), 0, VK_INDEX_TYPE_UINT32);
    vkCmdDrawIndexed(cb, o.mesh->indexCount, 1, 0, 0, 0);
  }
  vkCmdEndRenderPass(cb);
  // Copy the targets into the two planes of this slice of the G-buffer buffer.
  const std::pair<const Image*, VkDeviceSize> targets[2] = {{&gSurface_, 0}, {&gDetail_, detailOffset_}};
  for (const auto& [target, offset] : targets) {
    VkBufferImageCopy region{};
    region.bufferOffset = sliceStride_ * slice + offset;
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {width_, height_, 1};
    vkCmdCopyImageToBuffer(cb, target->handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, gbuffer_.handle(), 1, &region);
  }
  slicesReady_ |= 1u << slice;
}

void LocalView::recordBackground(VkCommandBuffer cb, const PixelRect& rect, uint32_t slice, uint32_t count,
                                 bool firstPass, bool blocks) {
  if (rect.width == 0 || rect.height == 0) return;
  ComputePush push = basePush();
  const bool visible = scene_.environment.visible;
  // A hidden environment still has samples where an edge pixel misses the object (radiance 0,
  // but they count): the constant kernel at intensity 0 adds them without any lookup.
  if (!visible) push.env[0] = 0.0f;
  const glm::vec2 jitter = count == 0 ? glm::vec2(0.0f) : jitterOffset(slice, jitterCount_);
  push.tone[2] = jitter.x;
  push.tone[3] = jitter.y;
  push.frame[2] = static_cast<uint32_t>(stats_.spp);  // index of the pass's first sample
  push.frame[3] = count;                              // 0: the once-per-restart write
  push.target[2] = rect.x | (rect.y << 16);
  push.target[3] = (firstPass ? 1u : 0u) | (blocks ? 2u : 0u);
  // The per-pass use goes over the edge list once it is known (see the kernel).
  const bool list = count > 0 && edgeListKnown_;
  if (list && edgeCount_ == 0) return;
  push.target[0] = list ? edgeCount_ : 0u;
  vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, r_->backgroundPipeline(env_->constant || !visible));
  vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_COMPUTE, r_->computeLayout(), 0, 1, &viewSets_[slice], 0, nullptr);
  vkCmdPushConstants(cb, r_->computeLayout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
  const uint32_t scale = blocks ? 2 : 1;
  if (list)
    vkCmdDispatch(cb, groups(edgeCount_, kShadeGroup * kShadeGroup), 1, 1);
  else
    vkCmdDispatch(cb, groups(groups(rect.width, scale), kShadeGroup), groups(groups(rect.height, scale), kShadeGroup),
                  1);
}

void LocalView::recordPending(VkCommandBuffer cb, uint32_t slice, bool resuming, bool preview) {
  // Slice 0 carries the coverage the resolve and the once-per-restart background use.
  const bool raster = (slicesReady_ & 1u) == 0 || (slicesReady_ & (1u << slice)) == 0;
  if ((slicesReady_ & 1u) == 0) recordRaster(cb, 0);
  if ((slicesReady_ & (1u << slice)) == 0) recordRaster(cb, slice);
  const bool firstPass = stats_.passes == 0 && !resuming;  // a resumed first pass keeps its NaN count
  if (clearPending_) vkCmdFillBuffer(cb, accum_.handle(), 0, VK_WHOLE_SIZE, 0);
  if (firstPass) vkCmdFillBuffer(cb, counters_.handle(), 0, VK_WHOLE_SIZE, 0);
  if (raster || clearPending_ || firstPass)
    memoryBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                  VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  // Deterministic outside the objects' bounds: written once per restart, not every pass. A
  // preview writes it at its own resolution, one lookup per 2x2 block (a good part of a dragged
  // camera's restart on lavapipe), and leaves the full one to the next pass.
  const bool background = (clearPending_ || (blockBackground_ && !preview)) && scene_.environment.visible;
  const bool blocks = clearPending_ && preview;
  blockBackground_ = preview ? blockBackground_ || blocks : false;
  if (background) {
    recordBackground(cb, PixelRect{0, 0, width_, height_}, 0, 0, false, blocks);
    memoryBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                  VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  }
}

void LocalView::recordResolve(VkCommandBuffer cb, bool linear) {
  ComputePush push = basePush();
  push.target[2] = linear ? 1u : 0u;
  vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, r_->resolvePipeline());
  vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_COMPUTE, r_->computeLayout(), 0, 1, &viewSets_[0], 0, nullptr);
  vkCmdPushConstants(cb, r_->computeLayout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
  vkCmdDispatch(cb, groups(width_, kResolveGroup), groups(height_, kResolveGroup), 1);
}

ErrorSums LocalView::deviceErrorSums() const {
  const auto* partials = static_cast<const float*>(partials_.mapped());
  const size_t n = partialCount(width_, height_);
  ErrorSums sums;
  for (size_t i = 0; i < n; ++i) {
    sums.variance += partials[4 * i + 0];
    sums.luminance += partials[4 * i + 1];
    sums.pixels += partials[4 * i + 2];
  }
  return sums;
}

HostResolveInput LocalView::hostResolveInput() const {
  HostResolveInput in;
  in.accum = static_cast<const float*>(accum_.mapped());
  in.surface = static_cast<const uint32_t*>(gbuffer_.mapped());  // slice 0's surface plane
  in.pixels = size_t(width_) * height_;
  in.exposureScale = std::exp2(scene_.render.exposure);
  in.toneMap = scene_.render.toneMap;
  return in;
}

void LocalView::setRelError(const ErrorSums& sums) {
  double e = relativeError(sums);
  if (e >= 0)
    stats_.relError = e;
  else
    stats_.relError.reset();
  stats_.relErrorSpp = stats_.spp;
  stats_.relErrorElapsedMs = stats_.elapsedMs;
  stats_.errorPixels = sums.pixels > 0 ? static_cast<uint64_t>(sums.pixels) : 0;
  stats_.errorMeanLuminance = sums.pixels > 0 ? sums.luminance / sums.pixels : 0.0;
  sinceErrorMs_ = 0;
}

// Covered pixels of each object's 8x8 workgroups in G-buffer slice 0, where the host can read
// it (CPU devices, whose resolve runs on the host): a tile's cost is in proportion to them, not
// to its area, since an invocation off the object returns at once and an object's bounds can
// be half empty (a sphere's corners, a torus).
void LocalView::measureCoverage() {
  coverageKnown_ = true;
  const auto* surface = static_cast<const uint32_t*>(gbuffer_.mapped());
  if (!surface) return;  // device-local: every invocation counts as covered
  for (size_t i = 0; i < objects_.size(); ++i) {
    ObjectState& o = objects_[i];
    const PixelRect& r = o.pixels;
    const uint32_t gx = groups(r.width, kShadeGroup);
    o.cover.assign(size_t(gx) * groups(r.height, kShadeGroup), 0);
    for (uint32_t y = r.y; y < r.y + r.height; ++y)
      for (uint32_t x = r.x; x < r.x + r.width; ++x)
        if ((surface[2 * (size_t(y) * width_ + x)] & ~kLeftHandedBit) == i + 1)
          ++o.cover[size_t((y - r.y) / kShadeGroup) * gx + (x - r.x) / kShadeGroup];
  }
}

void LocalView::listEdgePixels() {
  const auto* slices = static_cast<const uint8_t*>(gbuffer_.mapped());
  auto* list = static_cast<uint32_t*>(edgeList_.mapped());
  const uint32_t all = (1u << jitterCount_) - 1;
  if (!slices || !list || jitterCount_ < 2 || (slicesReady_ & all) != all) return;
  uint32_t n = 0;
  const PixelRect& r = coverRect_;
  for (uint32_t y = r.y; y < r.y + r.height; ++y)
    for (uint32_t x = r.x; x < r.x + r.width; ++x) {
      const size_t pixel = size_t(y) * width_ + x;
      uint32_t covered = 0;
      for (uint32_t s = 0; s < jitterCount_; ++s)
        covered += reinterpret_cast<const uint32_t*>(slices + sliceStride_ * s)[2 * pixel] != 0 ? 1 : 0;
      if (covered != 0 && covered != jitterCount_) list[n++] = static_cast<uint32_t>(pixel);
    }
  edgeCount_ = n;
  edgeListKnown_ = true;
}

// A pass is split into submissions of about ctx().submissionTargetMs(fence) of device time each, so
// that between two of them the other views' submissions get the queue (VkContext hands it over
// in arrival order): a heavy scene slows its own view, not the others. Each submission shades
// a run of tiles: whole rows of 8x8 workgroups of an object's bounds, or part of one row.
// Tiles start on the object's workgroup grid, so they are disjoint and together dispatch
// exactly the workgroups of the unsplit dispatch (the kernel only bounds-checks against the
// image: a tile ending mid-group inside the bounds would shade some pixels twice).
// Where one workgroup at the pass's sample count would already pass the target, the samples
// are split too: the pass sweeps the objects several times, each sweep taking the next samples
// of the sequence (frame[2] advanced), so a pass still adds `count` samples to every pixel and
// the result differs from the unsplit pass only in the order of float additions.
Result<FrameStats> LocalView::renderPass(double frameTargetMs) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!hasScene_) return makeError(ErrorCode::InvalidArgument, "no scene has been set");
  return passLocked(true, frameTargetMs);
}

Result<FrameStats> LocalView::passLocked(bool interruptible, double frameTargetMs) {
  stats_.passInProgress = false;
  updateDone();
  if (stats_.done()) {
    // max_samples lowered below an interrupted pass: its samples stay where they were taken
    // (each pixel's mean divides by its own count), the rest of it is not needed.
    partial_.reset();
    return stats_;
  }
  PassPlan plan = planPass(interruptible, frameTargetMs);
  Sweep sweep = startSweep(plan);
  auto complete = runSweep(plan, sweep);
  if (!complete) return complete.takeError();
  if (!*complete) return stats_;  // left partway: partial_ holds where it stands
  return finishPass(plan, sweep);
}

double LocalView::groupUnits(const ObjectState& o, size_t group, uint32_t n, bool preview) {
  // One unit per sample of a covered pixel: an invocation off the object costs next to nothing
  // against a loop-heavy BRDF's sample, the case the split is for. One unit per workgroup
  // keeps empty tiles from being free.
  const double covered = o.cover.empty() || preview ? kShadeGroup * kShadeGroup : o.cover[group];
  return covered * n + 1.0;
}

uint32_t LocalView::gridX(const ObjectState& o, uint32_t scale) {
  return groups((o.pixels.width + scale - 1) / scale, kShadeGroup);
}

uint32_t LocalView::gridY(const ObjectState& o, uint32_t scale) {
  return groups((o.pixels.height + scale - 1) / scale, kShadeGroup);
}

// Decides what the pass does before its first submission: resumes an interrupted pass with its
// own samples, slice and sweep size, or picks a new pass's kind (preview, first sample or a
// pass of the programs), sample count, G-buffer slice and samples per sweep. Takes over
// partial_ and clears a provisional first sample's count; lists the edge pixels between passes.
LocalView::PassPlan LocalView::planPass(bool interruptible, double frameTargetMs) {
  PassPlan p;
  p.interruptible = interruptible;
  p.frameTargetMs = frameTargetMs;
  p.t0 = std::chrono::steady_clock::now();
  p.resumed = std::move(partial_);
  partial_.reset();
  const std::optional<PartialPass>& resumed = p.resumed;
  const uint64_t maxSamples = static_cast<uint64_t>(scene_.render.maxSamples);
  // The first pass by the programs replaces a first sample (RenderSettings::firstSampleKernel):
  // it overwrites (passes is still 0), and the count starts again from it.
  if (stats_.provisional) {
    stats_.spp = 0;
    stats_.provisional = false;
  }
  // Between passes only, so that how a pass is split into submissions never changes the image.
  if (!resumed && !edgeListKnown_) listEdgePixels();
  // Passes after a restart ramp up 1, 2, 4, ... samples to samples_per_frame, so the first
  // frame of a change arrives quickly.
  const uint64_t ramp = stats_.passes < 20 ? (uint64_t(1) << stats_.passes) : UINT64_MAX;
  // A preview (RenderSettings::previewPass) shades one sample at one pixel of each 2x2
  // block, over workgroups of 16x16 pixels: `scale` 2; by the program, or by the preview
  // kernel where the program has not run yet (buildObjects).
  p.preview = previewPending_;
  // A first sample (RenderSettings::firstSampleKernel): one sample per pixel, by the preview
  // kernel where a program has not run yet.
  p.firstSample = firstSamplePending_ && !resumed;
  p.scale = p.preview ? 2 : 1;
  p.count = p.preview || p.firstSample ? 1
            : resumed                  ? resumed->count
                                       : static_cast<uint32_t>(std::min<uint64_t>(
                            {static_cast<uint64_t>(scene_.render.samplesPerFrame), ramp, maxSamples - stats_.spp}));
  if (frameTargetMs > 0 && !p.preview && !p.firstSample && !resumed) p.count = sizer_.fit(frameTargetMs, p.count);
  p.slice = resumed ? resumed->slice : sliceForPass(stats_.passes);
  p.firstPass = stats_.passes == 0;
  // Refresh the error estimate in the last submission when it is due (and a second half exists).
  p.refreshError = resumed ? resumed->refreshError
                           : !p.preview && stats_.passes >= 1 &&
                                 (sinceErrorMs_ >= kErrorRefreshMs || stats_.spp + p.count >= maxSamples);
  // A watched pass that outlasts its frame (even one sample: a costly BRDF, or mis at 512^2 on
  // a CPU device) returns at a submission boundary once the frame's time is spent, so the
  // stream shows a frame partway and this goes on at the next call. Not the first pass after a
  // restart: it overwrites, and the pixels it has not reached still hold the previous image.
  p.sliced = frameTargetMs > 0 && interruptible && !p.preview && stats_.passes >= 1;

  // Objects whose preview comes from the preview kernel (buildObjects).
  p.byPreviewKernel.assign(objects_.size(), false);
  for (size_t i = 0; (p.preview || p.firstSample) && i < objects_.size(); ++i)
    p.previewKernelPass |= p.byPreviewKernel[i] = objects_[i].previewKernel && !objects_[i].kernel->dispatched;

  p.targetMs = r_->ctx().submissionTargetMs(cmd_.fence());
  // Samples per sweep; a sweep in progress goes on with the same samples.
  p.chunk = resumed ? resumed->chunk : submissionSizer_.samplesPerSweep(p.targetMs, p.count, kShadeGroup * kShadeGroup);
  for (size_t i = 0; i < objects_.size(); ++i) {
    const ObjectState& o = objects_[i];
    if (o.pixels.width == 0 || o.pixels.height == 0) continue;
    p.visible.push_back(i);
    const size_t n = size_t(gridX(o, p.scale)) * gridY(o, p.scale);
    for (size_t g = 0; g < n; ++g) p.passUnits += groupUnits(o, g, p.count, p.preview);
  }
  return p;
}

// The sweep at the pass's start: at the beginning, or where a resumed pass stood, with the
// shade kernels' push constants for the pass's slice.
LocalView::Sweep LocalView::startSweep(const PassPlan& plan) const {
  Sweep s;
  s.push = basePush();
  // V is taken along the view ray through the sub-pixel position this slice was rasterized at.
  const glm::vec2 jitter = jitterOffset(plan.slice, jitterCount_);
  s.push.tone[2] = jitter.x;
  s.push.tone[3] = jitter.y;
  s.done = plan.visible.empty() ? plan.count : 0;
  if (const std::optional<PartialPass>& resumed = plan.resumed) {
    // The same scene geometry (a restart drops the partial pass): same objects.
    s.done = resumed->done, s.row = resumed->row, s.col = resumed->col, s.obj = resumed->obj;
    s.passDone = resumed->passDone;
  }
  // With RendererOptions::profilePasses each phase ends its submission, timed into `breakdown`.
  s.profile = r_->profilePasses();
  return s;
}

Result<void> LocalView::endPhase(Sweep& s, double& phaseMs) {
  if (!s.profile) return {};
  memoryBarrier(s.cb, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_ACCESS_MEMORY_WRITE_BIT,
                VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT);
  double ms = 0;
  BRDFA_TRY(cmd_.submitAndWait(&ms, /*viewPass=*/true));
  phaseMs += ms;
  auto begun = cmd_.begin();
  if (!begun) return begun.takeError();
  s.cb = *begun;  // each phase's recording binds what it uses
  return {};
}

// Runs the pass's submissions to its end, or until it is interrupted or its frame's time is
// spent: true when complete, false when left partway (partial_ then holds where it stands and
// stats_ its time). Each submission is sized by submissionSizer_, which learns from its time.
Result<bool> LocalView::runSweep(const PassPlan& plan, Sweep& s) {
  do {
    // Slice 0 recorded by an earlier submission (all waited for) is on the host's side now.
    if (plan.targetMs > 0 && !coverageKnown_ && (slicesReady_ & 1u)) measureCoverage();
    // A submission that rasterizes slice 0 shades nothing where the host will read the
    // coverage from it: shading before that would be sized by the bounds' area.
    const bool rasterOnly = plan.targetMs > 0 && !coverageKnown_ && gbuffer_.mapped() && (slicesReady_ & 1u) == 0;
    auto begun = cmd_.begin();
    if (!begun) return begun.takeError();
    s.cb = *begun;
    if (s.submissions == 0) {
      recordPending(s.cb, plan.slice, plan.resumed.has_value(), plan.preview);
      BRDFA_TRY(endPhase(s, s.breakdown.setupMs));
    } else  // the accumulators are read-modify-written; earlier submissions' writes come first
      memoryBarrier(s.cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                    VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    vkCmdBindDescriptorSets(s.cb, VK_PIPELINE_BIND_POINT_COMPUTE, r_->computeLayout(), 0, 1, &viewSets_[plan.slice], 0,
                            nullptr);
    SubmissionSizer::Request request;
    request.targetMs = plan.targetMs;
    request.passUnits = plan.passUnits;
    request.passDone = s.passDone;
    request.interactive = stats_.passes >= 1 && stats_.passes < kInteractivePasses;
    request.frameMs = plan.sliced ? plan.frameTargetMs : 0;  // two or more submissions per frame
    const SubmissionSizer::Budget budget = submissionSizer_.budget(request);
    double units = 0;
    if (!rasterOnly) {
      auto recorded = recordShading(plan, s, budget.units);
      if (!recorded) return recorded.takeError();
      units = *recorded;
    }
    BRDFA_TRY(endPhase(s, s.breakdown.shadeMs));
    if (s.done >= plan.count) BRDFA_TRY(recordPassEnd(plan, s));
    memoryBarrier(s.cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                  VK_ACCESS_HOST_READ_BIT);
    double ms = 0;
    BRDFA_TRY(cmd_.submitAndWait(&ms, /*viewPass=*/true));
    for (const ShadeKernel* k : s.bound) k->dispatched = true;
    s.bound.clear();
    clearPending_ = false;
    ++s.submissions;
    s.maxSubmissionMs = std::max(s.maxSubmissionMs, ms);
    s.passDone += units;
    submissionSizer_.record(units, ms, budget);
    if (leavePartway(plan, s, ms)) return false;
  } while (s.done < plan.count);
  return true;
}

// Records the shading of one submission: tiles of the objects' workgroup grids, from where the
// sweep stands, until `budget` units are taken (at least one workgroup) or the pass's samples
// are all swept. Advances the sweep; returns the units recorded.
Result<double> LocalView::recordShading(const PassPlan& plan, Sweep& s, double budget) {
  double units = 0;
  while (s.done < plan.count) {
    const size_t i = plan.visible[s.obj];
    const ObjectState& o = objects_[i];
    const uint32_t gx = gridX(o, plan.scale), gy = gridY(o, plan.scale);
    const uint32_t n = std::min(plan.chunk, plan.count - s.done);
    const Tiles tiles = chooseTiles(plan, s, units, budget);
    if (tiles.cols == 0) break;  // this submission is full
    BRDFA_TRY(dispatchTiles(plan, s, tiles, n));
    units += tiles.units;
    // Objects cover disjoint pixels, so their dispatches need no barrier between them; the
    // next sweep adds to the same pixels and does.
    s.col += tiles.cols;
    if (s.col == gx) {
      s.col = 0;
      s.row += tiles.rows;
    }
    if (s.row < gy) continue;
    s.row = 0;
    if (++s.obj < plan.visible.size()) continue;
    s.obj = 0;
    s.done += n;
    if (s.done < plan.count)
      memoryBarrier(s.cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                    VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  }
  return units;
}

// The next run of tiles of the current object from where the sweep stands, within what is
// left of `budget` after `units`: whole rows of workgroups while they fit, else part of one
// row (at least one workgroup per submission). No columns: the submission is full.
LocalView::Tiles LocalView::chooseTiles(const PassPlan& plan, const Sweep& s, double units, double budget) const {
  const size_t i = plan.visible[s.obj];
  const ObjectState& o = objects_[i];
  const uint32_t gx = gridX(o, plan.scale), gy = gridY(o, plan.scale);
  const uint32_t n = std::min(plan.chunk, plan.count - s.done);
  // A preview-kernel dispatch hands over through the scratch, one block per invocation
  // (a whole row of the image's blocks always fits: see resize).
  const uint32_t maxRows =
      plan.byPreviewKernel[i] ? std::max(1u, previewScratchBlocks_ / (gx * kShadeGroup * kShadeGroup)) : UINT32_MAX;
  Tiles t;
  if (s.col == 0) {
    for (uint32_t r = s.row; r < gy && t.rows < maxRows; ++r, ++t.rows) {
      double rowUnits = 0;
      for (uint32_t c = 0; c < gx; ++c) rowUnits += groupUnits(o, size_t(r) * gx + c, n, plan.preview);
      if (units + t.units + rowUnits > budget) break;
      t.units += rowUnits;
    }
    if (t.rows > 0) t.cols = gx;
  }
  if (t.rows == 0) {
    // A part of a row only where one row alone passes the budget: a tile's left and right
    // halves differ more than a row's (see dispatchTiles).
    if (s.col == 0 && units > 0) return Tiles{};
    t.rows = 1;
    for (uint32_t c = s.col; c < gx; ++c, ++t.cols) {
      const double g = groupUnits(o, size_t(s.row) * gx + c, n, plan.preview);
      if (units + t.units + g > budget && (t.cols > 0 || units > 0)) break;
      t.units += g;
    }
  }
  return t;
}

// Records the dispatches of `tiles` of the current object at `n` samples each, by its program
// or its preview kernel. A preview kernel's stages, the first time in the pass, each end a
// submission of their own (counted in the sweep).
Result<void> LocalView::dispatchTiles(const PassPlan& plan, Sweep& s, const Tiles& tiles, uint32_t n) {
  const size_t i = plan.visible[s.obj];
  const ObjectState& o = objects_[i];
  const VkPipelineLayout layout = r_->computeLayout();
  ComputePush& push = s.push;
  push.target[0] = static_cast<uint32_t>(i + 1);
  // First pass: overwrite, not add (per pixel); a preview (bit 1) overwrites too.
  push.target[3] = plan.preview ? 2u : plan.firstPass && s.done == 0 ? 1u : 0u;
  push.frame[2] = static_cast<uint32_t>(stats_.spp + s.done);  // the sequence continues across passes
  push.frame[3] = n;
  const ShadeKernel& kernel = plan.byPreviewKernel[i] ? *o.previewKernel : *o.kernel;
  s.bound.push_back(&kernel);
  vkCmdBindDescriptorSets(s.cb, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 1, 1, &o.set, 0, nullptr);
  // One dispatch per band, its rows permuted: llvmpipe hands each thread one contiguous
  // run of a dispatch's workgroups (lp_cs_tpool: two halves on two cores), and a band's
  // top and bottom halves can differ in cost several times over (near a sphere's pole).
  // Workgroup row y shades the band's row (y * step) mod rows, step ~ 0.618 rows and
  // coprime to it, so every contiguous run of workgroups takes rows spread over the whole
  // band and the threads finish together. Rows grouped into shorter dispatches instead cost
  // more per pass on a busy CPU, every dispatch waiting for all its threads.
  const uint32_t rows = tiles.rows;
  uint32_t step = 1;
  if (rows > 2) {
    step = std::max<uint32_t>(1, static_cast<uint32_t>(std::lround(rows * 0.6180339887)));
    while (std::gcd(step, rows) != 1) ++step;
  }
  const uint32_t permutation = rows | (step << 16);  // rows and step are below 4096 / 8
  std::memcpy(&push.cameraPos[3], &permutation, sizeof permutation);
  // Dispatch origin; images are at most 4096 wide.
  push.target[2] =
      (o.pixels.x + s.col * kShadeGroup * plan.scale) | ((o.pixels.y + s.row * kShadeGroup * plan.scale) << 16);
  vkCmdPushConstants(s.cb, layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
  if (!plan.byPreviewKernel[i]) {
    vkCmdBindPipeline(s.cb, VK_PIPELINE_BIND_POINT_COMPUTE, kernel.kernel->pipeline());
    vkCmdDispatch(s.cb, tiles.cols, rows, 1);
    return {};
  }
  // The preview kernel's three stages over one grid (kernels/preview.comp.glsl), each
  // reading what the one before wrote to the scratch; the next dispatch writes it again.
  const VkPipeline stages[3] = {r_->previewSetupPipeline(env_->constant), kernel.kernel->pipeline(),
                                r_->previewScatterPipeline()};
  for (int k = 0; k < 3; ++k) {
    vkCmdBindPipeline(s.cb, VK_PIPELINE_BIND_POINT_COMPUTE, stages[k]);
    vkCmdDispatch(s.cb, tiles.cols, rows, 1);
    memoryBarrier(s.cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                  VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    // The pass's first dispatch of each stage may carry its driver compile (the JIT, at
    // the first dispatch on lavapipe): each in a submission of its own, so the budget of
    // a submission meets one compile at a time, as in a program's first pass.
    if (s.previewStagesCompiled || k == 2) continue;
    double stageMs = 0;
    BRDFA_TRY(cmd_.submitAndWait(&stageMs, /*viewPass=*/true));
    ++s.submissions;
    s.maxSubmissionMs = std::max(s.maxSubmissionMs, stageMs);
    auto again = cmd_.begin();
    if (!again) return again.takeError();
    s.cb = *again;
    vkCmdBindDescriptorSets(s.cb, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 1, &viewSets_[plan.slice], 0, nullptr);
    vkCmdBindDescriptorSets(s.cb, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 1, 1, &o.set, 0, nullptr);
    vkCmdPushConstants(s.cb, layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
  }
  s.previewStagesCompiled = true;
  return {};
}

// Records what follows the pass's last samples in its last submission: the edge pixels'
// background samples, and the resolve when the error estimate is due (device resolve only).
Result<void> LocalView::recordPassEnd(const PassPlan& plan, Sweep& s) {
  // Inside the objects' bounds a pixel may be background in this slice and covered in
  // another (an edge): its background samples are taken with the pass, so the pixel is the
  // average over its sub-pixel positions. With one slice nothing changes from pass to pass.
  // A preview leaves them to the first pass: it shows the background the restart wrote.
  if (jitterCount_ > 1 && !plan.preview) recordBackground(s.cb, coverRect_, plan.slice, plan.count, plan.firstPass);
  BRDFA_TRY(endPhase(s, s.breakdown.edgeMs));
  if (plan.refreshError && !r_->hostResolve()) {
    memoryBarrier(s.cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                  VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
    recordResolve(s.cb, false);
    BRDFA_TRY(endPhase(s, s.breakdown.resolveMs));
  }
  return {};
}

// After a submission of an unfinished pass: leaves the pass partway, keeping its place in
// partial_ and its time in stats_, when interruptPass() asked for it (never a preview or first
// sample) or when a watched pass's next submission would pass its frame target. True when left.
bool LocalView::leavePartway(const PassPlan& plan, const Sweep& s, double submissionMs) {
  // A preview or first sample is not interrupted: it is short, and under changes coming
  // faster than it (a camera dragged), interrupting it would leave nothing to show at all.
  const bool interrupted = s.done < plan.count && plan.interruptible && !plan.preview && !plan.firstSample &&
                           interruptRequested_.exchange(false);
  // At the frame target: the next submission (about as long as this one) would pass it.
  const bool frameSpent = s.done < plan.count && plan.sliced && msSince(plan.t0) + submissionMs > plan.frameTargetMs;
  if (!interrupted && !frameSpent) return false;
  // Keep the place; spp counts the pass once complete.
  const double segmentMs = msSince(plan.t0);
  partial_ = PartialPass{plan.count,
                         plan.slice,
                         plan.chunk,
                         s.done,
                         s.row,
                         s.col,
                         s.obj,
                         s.passDone,
                         (plan.resumed ? plan.resumed->ms : 0.0) + segmentMs,
                         plan.refreshError};
  stats_.elapsedMs += segmentMs;
  sinceErrorMs_ += segmentMs;
  stats_.passInProgress = !interrupted;  // interrupted: a scene change waits, nothing to show
  return true;
}

// Completes the pass's statistics once all its samples are swept: a preview counts in the
// render time only, a first sample stands provisionally for the first pass, and a pass adds
// its samples, its time (to the pass sizer after the interactive passes) and, when due, a new
// error estimate. After a pass by the preview kernel the submission costs are learned again.
FrameStats LocalView::finishPass(const PassPlan& plan, Sweep& s) {
  submissionSizer_.passEnded();               // one pass to settle on the new cost
  const double segmentMs = msSince(plan.t0);  // this call's part of the pass
  const double passMs = segmentMs + (plan.resumed ? plan.resumed->ms : 0.0);
  PassBreakdown& breakdown = s.breakdown;
  auto timed = [&] {
    stats_.elapsedMs += segmentMs;
    stats_.lastPassMs = passMs;
    stats_.submissions = s.submissions;
    stats_.maxSubmissionMs = s.maxSubmissionMs;
  };
  // What a pass by the preview kernel learned is that kernel's cost: the scene's programs are
  // still to be compiled (their first submission a warm-up) and measured, as after a change of
  // program.
  auto programsNext = [&] {
    submissionSizer_.forget();
    for (ObjectState& o : objects_) o.previewKernel.reset();
  };
  if (plan.preview) {  // counts in no statistic but the render time
    previewPending_ = false;
    if (plan.previewKernelPass) programsNext();
    stats_.preview = true;
    timed();
    if (s.profile) {
      breakdown.otherMs = passMs - breakdown.setupMs - breakdown.shadeMs - breakdown.edgeMs - breakdown.resolveMs;
      stats_.breakdown = breakdown;
    }
    return stats_;
  }
  stats_.preview = false;
  if (plan.firstSample) {
    // Not a pass (passes stays 0): the next one, by the programs, overwrites it.
    firstSamplePending_ = false;
    programsNext();
    stats_.spp = plan.count;
    stats_.provisional = true;
    timed();
    stats_.nanSamples = *static_cast<const uint32_t*>(counters_.mapped());
    stats_.breakdown = breakdown;
    return stats_;
  }
  // The first passes after a restart carry the restart's work or are split into short
  // submissions (kInteractivePasses): their times would read as a large fixed part.
  if (stats_.passes >= kInteractivePasses) sizer_.record(plan.count, passMs);
  stats_.spp += plan.count;
  stats_.passes += 1;
  timed();
  stats_.nanSamples = *static_cast<const uint32_t*>(counters_.mapped());
  sinceErrorMs_ += segmentMs;
  if (plan.refreshError) {
    const auto tResolve = std::chrono::steady_clock::now();
    setRelError(r_->hostResolve() ? resolveOnHost(hostResolveInput(), nullptr, nullptr) : deviceErrorSums());
    if (s.profile) breakdown.resolveMs += msSince(tResolve);
  }
  updateDone();
  if (s.profile) {
    const double total = msSince(plan.t0) + (plan.resumed ? plan.resumed->ms : 0.0);
    breakdown.otherMs = total - breakdown.setupMs - breakdown.shadeMs - breakdown.edgeMs - breakdown.resolveMs;
    stats_.lastPassMs = total;
  }
  stats_.breakdown = breakdown;
  return stats_;
}

FrameStats LocalView::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

Result<Frame> LocalView::readFrame(bool linear) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!hasScene_) return makeError(ErrorCode::InvalidArgument, "no scene has been set");
  // A pass left partway (interrupted, or at a frame target) is completed first where it is the
  // first after a restart: the pixels it has not reached yet still hold the previous image.
  // A later one shows as far as it got: each pixel's mean divides by its own sample count.
  if (partial_ && stats_.passes == 0) BRDFA_TRY(passLocked(false));
  const bool host = r_->hostResolve();
  // Before the first pass of a restart the accumulators may still hold the previous scene's
  // object pixels (a parameter change does not clear them): clear now. A preview or first
  // sample has overwritten every object pixel.
  if (stats_.passes == 0 && !stats_.preview && !stats_.provisional) clearPending_ = true;
  if (!host || (slicesReady_ & 1u) == 0 || clearPending_) {
    auto begun = cmd_.begin();
    if (!begun) return begun.takeError();
    VkCommandBuffer cb = *begun;
    recordPending(cb, 0);
    if (!host) recordResolve(cb, linear);
    memoryBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                  VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                  VK_ACCESS_HOST_READ_BIT);
    BRDFA_TRY(cmd_.submitAndWait());
    clearPending_ = false;
  }

  Frame frame;
  frame.width = static_cast<int>(width_);
  frame.height = static_cast<int>(height_);
  const size_t pixels = size_t(width_) * height_;
  frame.rgba8.resize(pixels * 4);
  if (linear) frame.rgba32f.resize(pixels * 4);
  ErrorSums sums;
  if (host) {
    sums = resolveOnHost(hostResolveInput(), frame.rgba8.data(), linear ? frame.rgba32f.data() : nullptr);
  } else {
    std::memcpy(frame.rgba8.data(), outRgba8_.mapped(), pixels * 4);
    if (linear) std::memcpy(frame.rgba32f.data(), outFloat_.mapped(), pixels * 16);
    sums = deviceErrorSums();
  }
  if (stats_.passes >= 2) setRelError(sums);
  frame.stats = stats_;
  return frame;
}

}  // namespace brdfa
