// One progressive render target: G-buffer, half accumulators, outputs, per-object state.
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "brdfa/renderer.h"

#include "assets/gpu_assets.h"
#include "core/scene_math.h"
#include "programs/compute_kernel.h"
#include "render/host_resolve.h"
#include "render/pass_sizer.h"
#include "render/submission_sizer.h"
#include "render/local_renderer.h"

namespace brdfa {

class LocalView final : public RenderView {
 public:
  explicit LocalView(std::shared_ptr<LocalRenderer> renderer);
  ~LocalView() override;

  Result<void> init();

  Result<void> setScene(const Scene& scene) override;
  void prepareScene(const Scene& scene) override { (void)prebuildKernels(scene); }
  using RenderView::renderPass;
  Result<FrameStats> renderPass(double frameTargetMs) override;
  FrameStats stats() const override;
  Result<Frame> readFrame(bool linear) override;
  void interruptPass() override;

 private:
  struct ObjectState {
    std::shared_ptr<const ShadeKernel> kernel;
    // The preview's program while `kernel` has never run on a device that compiles at the first
    // dispatch (LocalRenderer::shadeKernels); dropped after the preview.
    std::shared_ptr<const ShadeKernel> previewKernel;
    ShadeVariant variant;  // what the kernel runs, for the stats' estimator and warnings
    std::shared_ptr<const GpuMesh> mesh;
    std::shared_ptr<const GpuTexture> textures[kMaxTextures];  // null: white
    std::shared_ptr<const GpuMeasured> measured;               // a measured BRDF's table, else null
    Buffer params;                                             // std140 BrdfParams
    Buffer transform;                                          // ObjectUniform
    VkDescriptorSet set = VK_NULL_HANDLE;
    PixelRect pixels;  // where the shading dispatch runs (the object's screen bounds)
    // Covered pixels of each 8x8 workgroup of `pixels`, row-major (empty: not measured, count
    // all 64): what a tile of the split pass costs (see measureCoverage).
    std::vector<uint32_t> cover;
  };

  // A pass interrupted between two submissions (interruptPass): where its sweep stood, so the
  // next pass completes it with the same samples. A restart drops it. Never a preview, which
  // is not interrupted (and a restart is what makes one pending).
  struct PartialPass {
    uint32_t count = 0, slice = 0, chunk = 0;  // the pass's samples, G-buffer slice, samples per sweep
    uint32_t done = 0, row = 0, col = 0;       // samples swept, workgroup row and column in the object
    size_t obj = 0;                            // index into the visible objects
    double passDone = 0;                       // cost units shaded so far
    double ms = 0;                             // wall time spent on it so far
    bool refreshError = false;
  };
  // What one pass does, decided before its first submission (planPass).
  struct PassPlan {
    bool interruptible = false;
    double frameTargetMs = 0;                  // as in renderPass (0: none)
    std::chrono::steady_clock::time_point t0;  // when this call's part of the pass began
    std::optional<PartialPass> resumed;        // the interrupted pass this one completes
    bool preview = false, firstSample = false, firstPass = false;
    bool refreshError = false;                 // the error estimate is refreshed at the pass's end
    bool sliced = false;                       // a watched pass: may return partway at its frame target
    uint32_t scale = 1;                        // pixels per dispatched invocation, per axis (2: a preview)
    uint32_t count = 0, slice = 0, chunk = 0;  // samples, G-buffer slice, samples per sweep
    std::vector<bool> byPreviewKernel;         // per object: shaded by its preview kernel
    bool previewKernelPass = false;            // some object is
    std::vector<size_t> visible;               // objects on screen
    double passUnits = 0;                      // the whole pass's cost units
    double targetMs = 0;                       // device time a submission aims at (0: no split)
  };
  // Where a pass's sweep stands and what its submissions measured (runSweep).
  struct Sweep {
    uint32_t done = 0, row = 0, col = 0;  // samples swept, workgroup row and column in the object
    size_t obj = 0;                       // index into the visible objects
    double passDone = 0;                  // cost units shaded so far
    ComputePush push{};                   // the shade kernels' push constants
    VkCommandBuffer cb = VK_NULL_HANDLE;  // the submission being recorded
    bool profile = false;                 // RendererOptions::profilePasses
    PassBreakdown breakdown;
    uint64_t submissions = 0;
    double maxSubmissionMs = 0;
    std::vector<const ShadeKernel*> bound;  // kernels the submission being recorded dispatches
    bool previewStagesCompiled = false;     // the preview kernel's stages have run in this pass
  };
  // A run of tiles of one object's workgroup grid, and its cost units.
  struct Tiles {
    uint32_t cols = 0, rows = 0;
    double units = 0;
  };

  // The pass of renderPass, under mutex_; an `interruptible` one ends early on interruptPass().
  // frameTargetMs as in renderPass (0: none). Plans the pass, sweeps it in submissions and
  // finishes its statistics, or leaves it partway.
  Result<FrameStats> passLocked(bool interruptible, double frameTargetMs = 0);
  PassPlan planPass(bool interruptible, double frameTargetMs);
  Sweep startSweep(const PassPlan& plan) const;
  Result<bool> runSweep(const PassPlan& plan, Sweep& s);
  Result<double> recordShading(const PassPlan& plan, Sweep& s, double budget);
  Tiles chooseTiles(const PassPlan& plan, const Sweep& s, double units, double budget) const;
  Result<void> dispatchTiles(const PassPlan& plan, Sweep& s, const Tiles& tiles, uint32_t n);
  Result<void> recordPassEnd(const PassPlan& plan, Sweep& s);
  bool leavePartway(const PassPlan& plan, const Sweep& s, double submissionMs);
  FrameStats finishPass(const PassPlan& plan, Sweep& s);
  // With profiling, ends the submission being recorded, adds its time to `phaseMs` and begins
  // the next; nothing otherwise.
  Result<void> endPhase(Sweep& s, double& phaseMs);
  // Cost units of workgroup `group` of `o`'s grid at `n` samples per pixel.
  static double groupUnits(const ObjectState& o, size_t group, uint32_t n, bool preview);
  // An object's dispatch grid: workgroups over its bounds (over its 2x2 blocks in a preview).
  static uint32_t gridX(const ObjectState& o, uint32_t scale);
  static uint32_t gridY(const ObjectState& o, uint32_t scale);
  // How a new scene differs from the view's (compareScene).
  struct SceneChange {
    bool sameShading = false;      // same programs, parameters, textures and lighting, same size
    bool samePrograms = false;     // same pipelines, in object order
    bool geometryChanged = false;  // camera, meshes, transforms or size
    bool lightingChanged = false;  // environment, sampling or seed
    bool restart = false;          // the image starts again
    bool displayChanged = false;   // exposure, tone map or the limits of the render
  };
  SceneChange compareScene(const Scene& scene, const std::vector<ObjectState>& objects, bool resized) const;
  void adoptScene(const Scene& scene, std::vector<ObjectState> objects, const SceneChange& change);
  void describeScene(uint64_t dropsBefore);
  // Sizes the view for width x height within the renderer's view-memory budget: a refused size
  // leaves the view as it was.
  Result<void> resize(uint32_t width, uint32_t height);
  Result<void> createTargets(uint32_t width, uint32_t height);
  Result<void> createBuffers(uint32_t width, uint32_t height, uint32_t scratchBlocks);
  void writeViewDescriptors();
  // `prebuilt`: prebuildKernels(scene), used where it holds an object's kernels.
  Result<std::vector<ObjectState>> buildObjects(
      const Scene& scene, const std::vector<std::optional<LocalRenderer::ShadeKernels>>& prebuilt);
  // The kernels of `scene`'s objects, in object order, built or found in the renderer's cache
  // without the view's lock; nullopt where that failed (buildObjects asks again and reports it).
  std::vector<std::optional<LocalRenderer::ShadeKernels>> prebuildKernels(const Scene& scene);

  void releaseObjects(std::vector<ObjectState>& objects);
  // Records what a scene change left pending: the raster pass of G-buffer slice 0 and of
  // `slice` into their G-buffer planes; clearing the accumulators and writing the background.
  // `resuming`: the first submission of an interrupted pass's remainder.
  // A `preview` pass writes the background at 2x2 blocks and leaves it pending at full
  // resolution (blockBackground_) for the next pass or frame read.
  void recordPending(VkCommandBuffer cb, uint32_t slice, bool resuming = false, bool preview = false);
  void recordRaster(VkCommandBuffer cb, uint32_t slice);
  // The background where no object can be (outside every object's screen bounds) is written
  // once per restart; inside those bounds it is sampled each pass with that pass's jitter.
  // `blocks`: the once-per-restart write (count 0) at one lookup per 2x2 block (a preview).
  void recordBackground(VkCommandBuffer cb, const PixelRect& rect, uint32_t slice, uint32_t count, bool firstPass,
                        bool blocks = false);
  void recordResolve(VkCommandBuffer cb, bool linear);
  ErrorSums deviceErrorSums() const;  // from the resolve kernel's partial sums
  HostResolveInput hostResolveInput() const;
  void setRelError(const ErrorSums& sums);
  // Sets stats_.converged and maxSamplesReached from spp, rel_error and the scene's limits.
  void updateDone();
  // Entries of the error partial-sum buffer: one per subgroup of each resolve workgroup.
  size_t partialCount(uint32_t width, uint32_t height) const;
  ComputePush basePush() const;
  void measureCoverage();
  // Lists the edge pixels of the objects' bounds, background in some slices and covered in
  // others, once every slice is rasterized and host-visible (CPU devices). From then on the
  // edge kernel runs over them only: a pixel of the bounds that no slice covers keeps what the
  // first passes gave it, the background averaged over its sub-pixel positions.
  void listEdgePixels();

  std::shared_ptr<LocalRenderer> r_;
  mutable std::mutex mutex_;
  CommandContext cmd_;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  // Anti-aliasing: the visibility is rasterized at kMaxJitter sub-pixel offsets into as many
  // G-buffer slices (lazily, by the first passes after a geometry change), and pass p shades
  // slice sliceForPass(p). One view descriptor set per slice: bindings 0, 10 and 11 are that
  // slice. A slice holds the surface plane, then the detail plane at detailOffset_.
  static constexpr uint32_t kMaxJitter = 4;
  uint32_t jitterCount_ = 1;       // slices in use: kMaxJitter, or 1 for images above 1024^2 pixels
  VkDeviceSize sliceStride_ = 0;   // bytes from one slice to the next (offset-aligned)
  VkDeviceSize detailOffset_ = 0;  // bytes from a slice's start to its detail plane
  uint32_t slicesReady_ = 0;       // bit s: slice s holds the current geometry
  uint32_t sliceForPass(uint64_t pass) const;
  VkDescriptorSet viewSets_[kMaxJitter] = {};
  PixelRect coverRect_;  // union of the objects' screen bounds
  VkFramebuffer framebuffer_ = VK_NULL_HANDLE;
  Image gSurface_, gDetail_, depth_;
  Buffer gbuffer_, accum_, counters_, outRgba8_, outFloat_, partials_;
  // Pixel indices of the edge pixels (see listEdgePixels), host-written; room for every pixel.
  Buffer edgeList_;
  // The preview kernel's hand-over between its stages (binding 12): previewScratchBlocks_ blocks
  // of one dispatch, 6 x 16 bytes each (kernels/preview_setup.comp.glsl).
  Buffer previewScratch_;
  uint32_t previewScratchBlocks_ = 0;
  // Texel views of gbuffer_'s planes per slice and of accum_ (declared after the buffers:
  // destroyed before them).
  TexelView surfaceViews_[kMaxJitter], detailViews_[kMaxJitter], edgeView_;
  // edgeList_ holds the current geometry's edge pixels, edgeCount_ of them.
  bool edgeListKnown_ = false;
  uint32_t edgeCount_ = 0;
  uint32_t width_ = 0, height_ = 0;
  uint64_t reservedBytes_ = 0;  // of the renderer's view-memory budget, for the current size

  bool hasScene_ = false;
  Scene scene_;
  std::shared_ptr<const GpuEnvironment> env_;
  std::vector<ObjectState> objects_;
  bool clearPending_ = true;
  bool blockBackground_ = false;  // the background holds a preview's 2x2 blocks (recordPending)
  // Splits passes into submissions of about ctx().submissionTargetMs(fence) (see renderPass),
  // from what this view's own submissions cost.
  SubmissionSizer submissionSizer_;
  bool coverageKnown_ = false;  // ObjectState::cover is measured for the current geometry
  double sinceErrorMs_ = 0;     // pass time since rel_error was last refreshed
  PassSizer sizer_;             // what passes of each size took since the last restart (renderPass's frame target)
  FrameStats stats_;
  bool previewPending_ = false;      // the next pass is a preview (RenderSettings::previewPass)
  bool firstSamplePending_ = false;  // the next pass is a first sample (RenderSettings::firstSampleKernel)
  std::optional<PartialPass> partial_;
  std::atomic<bool> interruptRequested_{false};
};

}  // namespace brdfa
