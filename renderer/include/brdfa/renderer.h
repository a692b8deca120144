// The renderer library's entry point. No HTTP and no Vulkan types in this header: the server
// links against it, and it could later live in a separate worker process.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "brdfa/assets.h"
#include "brdfa/brdf.h"
#include "brdfa/duration_histogram.h"
#include "brdfa/result.h"
#include "brdfa/scene.h"

namespace brdfa {

// Where accumulators are resolved into frames: by a compute kernel, or by a C++ loop over the
// mapped accumulators (much faster on CPU devices, where device memory is host memory).
enum class ResolveMode { Auto, Device, Host };  // Auto: Host on CPU devices, Device on GPUs

struct RendererOptions {
  std::string deviceName;   // substring of the device name to pick; empty = prefer a real GPU
  std::string shaderDir;    // directory holding shaders/lib and shaders/kernels
  bool validation = false;  // enable VK_LAYER_KHRONOS_validation when present
  ResolveMode resolve = ResolveMode::Auto;
  // Device time one queue submission of a pass aims at: a pass is split into submissions of
  // about this length, so a heavy scene cannot hold the shared queue for long.
  // 0: one submission per pass.
  double submissionTargetMs = 50;
  // The target while no other view has used the queue in the last half second: then nobody
  // waits between submissions, and fewer of them save their wake-ups, which a loaded CPU makes
  // costly (a slider change's frame is slower under busy loops with the shorter target).
  // Kept far below the pass budget. 0: always submissionTargetMs.
  double soloSubmissionTargetMs = 250;
  // SPIR-V cache on disk (empty: memory only). loadCache false only writes it (--no-cache-load).
  std::string cacheDir;
  bool loadCache = true;
  // Measures where each pass's time goes (FrameStats::breakdown): every phase of a pass is
  // submitted and waited for on its own, which adds a little per phase. For benchmarks (bench/).
  bool profilePasses = false;
  // Points Mesa's shader disk cache here (sets MESA_SHADER_CACHE_DIR for this process unless it
  // is already set) before the device opens; empty leaves the driver's default.
  std::string driverCacheDir;
  // GLSL is compiled in brdfa-compile-worker processes, each compile under this budget; past
  // it the compile fails with a CompileError naming the budget.
  double compileSeconds = 5.0;
  size_t compileMemoryMiB = 1024;  // RSS of one compile worker (MemoryUse::Compiles counts them at it)
  size_t compileWorkers = 0;       // at once; 0: one per core, at least 2
  // Memory the renderer may take in all (RendererCounters::memory): the device process as it
  // starts (counted once more for each of spareProcesses, idle copies of it kept ready), render
  // targets and G-buffers of every view, meshes, textures and environments on the device,
  // uploads in flight to it, and compiled programs. What would pass it first drops unused
  // cached programs and assets (they are rebuilt when used again), then fails with OverBudget
  // naming what asked and what is left. 0: no budget.
  uint64_t memoryBudgetBytes = 0;
  std::string memoryBudgetLabel;  // names the budget in OverBudget messages (MemoryLedger)
  unsigned spareProcesses = 0;
  // Isolation: the device lives in a supervised brdfa-render-worker process. A
  // pipeline build past buildSeconds, one queue submission of a pass or frame read past
  // passSeconds (passes are split into submissions of ~50 ms; a program's first submission also
  // carries the driver's compile on lavapipe, long for a large BRDF), one submission of a
  // check past checkSeconds, or the worker's resident memory past workerMemoryBytes, kills and
  // restarts the worker; the program that caused it is quarantined (its requests then fail
  // with RenderBudget naming the program and the budget) and every other view is restored from its scene on its
  // next call. False: the device lives in this process (tests, tools).
  bool isolate = false;
  double buildSeconds = 10.0;
  // While one submission runs, every other view waits: this bounds the class's frame gaps.
  double passSeconds = 1.5;
  double checkSeconds = 120.0;
  uint64_t workerMemoryBytes = 0;  // 0: memoryBudgetBytes + 2 GiB (or no limit without one)
};

struct DeviceInfo {
  std::string name;        // e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string type;        // "cpu" | "gpu"
  std::string driver;      // driver name and version string
  std::string apiVersion;  // e.g. "1.3.230"
};

struct CompileInfo {
  std::vector<Diagnostic> warnings;
  double compileMs = 0;  // glslang time (0 when served from the SPIR-V cache)
  bool cached = false;
};

// Progress of one RenderView's accumulation.
// Where the latest pass's time went, with RendererOptions::profilePasses (else all 0). Device
// phases are host-timed submissions (lavapipe's timestamps read ~0 for long dispatches).
struct PassBreakdown {
  double setupMs = 0;    // raster of pending G-buffer slices, clears, the once-per-restart background
  double shadeMs = 0;    // the objects' shade kernels
  double edgeMs = 0;     // background samples of edge pixels (anti-aliasing)
  double resolveMs = 0;  // the error estimate's resolve, on the device or the host
  double otherMs = 0;    // the rest of the pass's wall time: recording, submission, fence waits
};

struct FrameStats {
  uint64_t spp = 0;       // samples per pixel accumulated since the last scene change
  uint64_t passes = 0;    // progressive passes since the last scene change
  double elapsedMs = 0;   // render time spent since the last scene change
  double lastPassMs = 0;  // wall time of the latest pass
  // The latest pass's queue submissions (RendererOptions::submissionTargetMs) and the device
  // time of its longest one (wall time from submit to done where the queue has no timestamps).
  uint64_t submissions = 0;
  double maxSubmissionMs = 0;
  PassBreakdown breakdown;  // of the latest pass, with RendererOptions::profilePasses
  uint64_t nanSamples = 0;  // NaN/Inf samples dropped since the last scene change
  // Relative RMS error of the image, estimated from two statistically independent half
  // accumulators: sqrt(mean over object pixels of the mean's variance) / mean luminance.
  std::optional<double> relError;
  uint64_t relErrorSpp = 0;  // spp when relError was last measured (refreshed every ~200 ms)
  // The pixels relError was measured over (covered by an object, with samples in both halves)
  // and their mean luminance, at the same moment: relError * meanLuminance is the RMS standard
  // error of those pixels (a difference of two images needs it, frame_difference.h).
  uint64_t errorPixels = 0;
  double errorMeanLuminance = 0;
  double relErrorElapsedMs = 0;  // elapsedMs at that moment
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  uint64_t programBytes = 0;       // SPIR-V size of the scene's distinct shading programs
  bool converged = false;          // rel_error <= render.target_error (never without a target)
  bool maxSamplesReached = false;  // spp reached render.max_samples
  bool done() const { return converged || maxSamplesReached; }  // no more passes will run
  // The estimator the objects run, e.g. "mis(environment+brdf)", "mis(environment+cosine)",
  // "brdf", "cosine", "legacy"; several distinct ones are joined with ", ".
  std::string estimator;
  // Why the estimator differs from the requested mode (a sampler without pdfBRDF cannot take
  // part in MIS, a BRDF without a sampler falls back to cosine).
  std::vector<std::string> warnings;
  uint64_t sceneVersion = 0;  // increments on every setScene that changed the scene
  // The image is a preview (RenderSettings::previewPass): no pass since the last restart
  // yet, spp 0, but a frame read shows one sample per 2x2 block of pixels.
  bool preview = false;
  // spp is 1, taken by the preview kernel (RenderSettings::firstSampleKernel); the next pass
  // replaces that sample, and spp counts from it. Never done while provisional.
  bool provisional = false;
  // The latest renderPass returned partway through its pass, at its frame target (renderPass):
  // a frame read now shows the pass's samples where it has been. spp counts the pass once done.
  bool passInProgress = false;
};

// A resolved frame read back from the device.
struct Frame {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba8;  // tone-mapped sRGB (exposure applied), row 0 at the top
  std::vector<float> rgba32f;  // linear radiance, row 0 at the top; filled only when asked
  FrameStats stats;
};

// One progressive render target with its own scene and accumulators (a session, or a one-shot
// render). All methods are thread-safe: calls on one view are serialized by the view.
class RenderView {
 public:
  virtual ~RenderView() = default;

  // Applies a scene. Compiles the BRDFs it needs (served from the cache when seen before) and
  // uploads what changed. Accumulation restarts when the image changes: camera, geometry,
  // environment, sampling, image size, a BRDF or a parameter value. Exposure,
  // samples_per_frame and max_samples keep it (lowering max_samples below the samples taken
  // leaves spp above it, done; target_error likewise). A change of parameter values only never recompiles. An
  // identical scene changes nothing. On error the previous scene stays in place.
  virtual Result<void> setScene(const Scene& scene) = 0;
  // Builds what setScene(scene) will need (its programs) without waiting for a pass in flight:
  // a setScene that follows finds them built. Optional (setScene builds whatever is missing,
  // and reports what fails). Never changes the view.
  virtual void prepareScene(const Scene& scene) { (void)scene; }

  // Renders one progressive pass of render.samples_per_frame samples per pixel: fewer in the
  // first passes after a restart (1, 2, 4, ...) and when max_samples is near. Does nothing once
  // done() (converged to render.target_error, or max_samples reached).
  // With frameTargetMs > 0 (a stream shows every pass), fewer again when the passes measured
  // since the last restart predict that the pass would take longer than that: the most
  // samples that fit, but never fewer than take as long as a pass's fixed part, and none
  // fewer where even those would take twice the target (more passes of fewer samples: a
  // higher frame rate for a little less throughput, each pass's fixed part paid more often).
  // Where even one sample per pixel takes longer than frameTargetMs (a costly BRDF, mis at
  // 512^2 on a CPU device), a pass after the first since the restart returns at a submission
  // boundary once the target is spent (stats().passInProgress), and the next call goes on
  // with it; how a pass is split never changes the image.
  virtual Result<FrameStats> renderPass(double frameTargetMs) = 0;
  Result<FrameStats> renderPass() { return renderPass(0.0); }

  virtual FrameStats stats() const = 0;

  // Resolves the accumulators into an image; `linear` also returns float radiance. A pass left
  // incomplete (interruptPass(), or a frame target) is completed first if it is the first pass
  // since the restart, whose pixels not yet reached still hold the previous image; a later one
  // is shown as far as it got (each pixel's mean divides by its own sample count).
  virtual Result<Frame> readFrame(bool linear) = 0;

  // Asks the pass in progress, or else the next one, to stop at its next queue-submission
  // boundary and return (its samples not yet counted in spp), so that a setScene() waiting for
  // the view gets it after one submission instead of a whole pass. A preview pass
  // (RenderSettings::previewPass) runs to its end. The next renderPass() or
  // readFrame() completes the interrupted pass with the same samples, unless a setScene() that
  // restarts accumulation drops it. setScene() withdraws a request no pass has taken yet.
  // Never blocks. The first passes after a restart are split into short submissions so that
  // this takes effect promptly while a user is changing the scene.
  virtual void interruptPass() {}
};

// What the renderer's memory holds now, by use, against its budget (RendererOptions).
struct MemoryUsage {
  uint64_t budget = 0;         // RendererOptions::memoryBudgetBytes (0: none)
  uint64_t fixed = 0;          // the device process and its idle compile workers at start (times 1 + spareProcesses)
  uint64_t renderTargets = 0;  // every view's G-buffer, accumulators and outputs
  uint64_t assets = 0;         // meshes, textures, environments and measured tables on the device
  uint64_t transfers = 0;      // uploads in flight to the device (decoded data, staging)
  uint64_t programs = 0;       // built pipelines (an estimate each) and cached SPIR-V
  uint64_t compiles = 0;       // what the GLSL compile workers may grow to, at their budget
  uint64_t droppedBytes = 0;   // unused cached programs and assets dropped to fit, since start
  uint64_t drops = 0;          // how many times that happened
  std::string lastDropped;     // what the last drop gave back, for a person
  uint64_t total() const { return fixed + renderTargets + assets + transfers + programs + compiles; }
};

// Work the renderer has done since it started: what tests and operators use to see that a
// change did (or did not) compile anything.
struct RendererCounters {
  uint64_t glslCompiles = 0;         // GLSL -> SPIR-V runs (SPIR-V cache misses)
  uint64_t glslCompileErrors = 0;    // of those, the ones that failed (error, time or memory limit)
  DurationHistogram compileTime;     // wall time of each of those runs
  uint64_t spirvCacheHits = 0;       // from memory
  uint64_t spirvDiskHits = 0;        // from the disk cache
  uint64_t pipelinesCreated = 0;     // shading pipelines built (each costs a driver JIT)
  MemoryUsage memory;                // now, against RendererOptions::memoryBudgetBytes
  uint64_t workerRestarts = 0;       // isolated renderers: render workers killed and replaced
  uint64_t quarantinedPrograms = 0;  // isolated renderers: programs refused since (see RendererOptions)

  // Isolated renderers: the requests to the render worker since start, per operation
  // ("renderPass", "readFrame", ...). A request's round trip is the time from its write here to
  // its reply read here; of that, the worker waited `workerQueueSeconds` for a thread to take it
  // and took `workerServeSeconds` to serve it. The rest is the channel: copies, the socket, and
  // the wake-ups of the threads on both ends.
  struct ChannelOp {
    uint64_t requests = 0;
    uint64_t bytesToWorker = 0;
    uint64_t bytesFromWorker = 0;
    double roundTripSeconds = 0;
    double workerQueueSeconds = 0;
    double workerServeSeconds = 0;
  };
  std::map<std::string, ChannelOp> channel;
  double channelInFlightSeconds = 0;  // requests in flight, integrated over time
  uint64_t channelMaxInFlight = 0;    // the most in flight at once

  // Adds the figures that only ever grow (compiles, cache hits, pipelines) of `other`: an
  // isolated renderer keeps those of the workers it replaced, so they never go back.
  void addCumulative(const RendererCounters& other) {
    glslCompiles += other.glslCompiles;
    glslCompileErrors += other.glslCompileErrors;
    compileTime.merge(other.compileTime);
    spirvCacheHits += other.spirvCacheHits;
    spirvDiskHits += other.spirvDiskHits;
    pipelinesCreated += other.pipelinesCreated;
  }
};

// One property a file may claim (BrdfClaims), as checked: measured always, failed only when
// claimed.
struct ClaimVerdict {
  std::string name;  // "reciprocity" | "energy-conservation" | "non-negativity"
  bool claimed = false;
  bool holds = true;     // the measurement is within the property's limit (below)
  std::string measured;  // the figure and its worst case, for a person
};

// Numeric checks of one BRDF on the device, through a compute
// kernel that evaluates the same BRDF() code the renderer shades with. Directions: a grid over
// view and light polar angles up to 89.9 degrees and exactly 90, and azimuths (L = -V on the
// horizon, where the half vector is 0/0, is left out and counted); parameters: every parameter
// at its minimum, maximum and default (one varied at a time, others at default). The albedo at
// each view and setting comes from lib/albedo.glsl (importance sampling with the file's
// sampler, else a cosine + half-vector mixture; 8 x 1024 samples) with its standard error.
// Limits: reciprocity holds when every relative error is <= kReciprocityLimit; energy
// conservation when no albedo exceeds 1 by more than 3 standard errors (+ kAlbedoSlack for
// float rounding); non-negativity when no channel is < 0. NaN and Inf always fail.
struct BrdfCheckReport {
  static constexpr double kReciprocityLimit = 1e-3, kAlbedoSlack = 1e-3, kAlbedoSigmas = 3.0;
  uint64_t evaluations = 0;
  uint64_t nanCount = 0;
  uint64_t infCount = 0;
  uint64_t negativeCount = 0;      // any channel < 0
  double maxAlbedo = 0;            // largest directional albedo over view angles and settings
  double maxAlbedoStdError = 0;    // its standard error
  uint64_t albedoAboveOne = 0;     // (view angle, setting) pairs whose albedo is significantly > 1
  double maxReciprocityError = 0;  // max |f(L,V) - f(V,L)| / max(|f(L,V)|, |f(V,L)|, 1e-6)
  uint64_t leftOut = 0;            // (L, V) pairs of measure zero not evaluated: L = -V on the horizon
  // Where the worst case of each finding is, for a person: the parameter setting, the view and
  // light directions (polar angle from N, azimuth from X) and the values. Empty when none.
  std::string worstReciprocity;      // where maxReciprocityError was found (when > 0)
  std::string firstBadValue;         // the first NaN, Inf or negative value met
  std::string worstAlbedo;           // where maxAlbedo was found, with its standard error
  std::vector<ClaimVerdict> claims;  // the three properties, in the order above
  double ms = 0;                     // wall time of the check
  bool ok() const {
    if (nanCount != 0 || infCount != 0) return false;
    for (const ClaimVerdict& c : claims)
      if (c.claimed && !c.holds) return false;
    return true;
  }
};

// Checks of a file's sampleBRDF() (in many frames and views), at default
// parameters, in every configuration of SamplerCheckConfig below (samplesPerConfiguration each).
// Always run, using only what must hold if the reported pdf is the density of the samples: over
// 128 cells of equal solid angle, the mean of 1_cell / pdf equals the cell's solid angle
// (z-scores; views up to 70 degrees, cells with cos(theta) >= 1/4, or >= 3/8 at views beyond 45
// degrees: elsewhere 1/pdf is too heavy-tailed, see brdf_check.cpp); the importance-sampled albedo
// E[f cos / pdf] equals a cosine-sampled estimate (a sampler that misses part of the lobe fails
// this); the returned value equals BRDF(); every L drawn with pdf > 0 is unit length
// (| |L| - 1 | < 1e-4) and above the horizon (N.L > 0; a sampler rejects a draw with pdf 0).
// When the sample section also defines pdfBRDF(L, V, N, X, Y) (the density of sampleBRDF's
// draws at any L), pbrt-v4's chi-square goodness-of-fit test runs too: per configuration, the
// counts of accepted samples in 10 x 20 cells uniform in theta (0..90 degrees) and phi against
// the counts pdfBRDF predicts (its Simpson integral over each cell times all draws, rejected
// ones included), small cells pooled, significance 0.01 Sidak-corrected over all
// configurations; and the pdf each sample returned must equal pdfBRDF there.
// The report's max* fields are the worst over all configurations; `configs` has each one's own
// figures and `worst` names the configuration and check closest to (or furthest past) its limit.

// One configuration: a shading frame (N, and X, Y orthonormal around it, as the integrator
// passes them) and a view direction V at viewDeg from N and viewAzimuthDeg from X.
struct SamplerCheckConfig {
  std::string normalLabel;  // "+z", "near +x (1e-3 rad)", "arbitrary", ...
  Vec3 normal{0, 0, 1}, tangent{1, 0, 0}, bitangent{0, 1, 0}, view{0, 0, 1};
  double viewDeg = 0, viewAzimuthDeg = 0;
  std::string describe() const;  // "normal +z (0, 0, 1), view 60 deg at azimuth 45 deg"
};

// The figures of one configuration, and its check nearest to failing: `worstCheck` is one of
// "value", "cell z", "albedo z", "chi2", "pdf mismatch", "length", "pdf below horizon";
// `worstSeverity` is its value over its limit (>= 1 fails; for chi2 log(p) / log(threshold)).
struct SamplerConfigResult {
  SamplerCheckConfig config;
  uint64_t rejected = 0;
  double maxValueMismatch = 0, maxCellZ = 0, albedoZ = 0, maxPdfMismatch = 0, maxLengthError = 0;
  uint64_t pdfBelowHorizon = 0;
  double chi2PValue = 1;  // 1 when the chi-square test did not run
  std::string chi2Failure;
  std::string worstCheck;
  double worstValue = 0, worstSeverity = 0;
};

struct SamplerCheckReport {
  uint64_t samples = 0;
  uint64_t rejected = 0;        // pdf = 0, or L on or below the horizon
  double maxValueMismatch = 0;  // max relative |returned f - BRDF(L, V)|
  uint32_t cellsTested = 0;     // cells with enough samples to test
  double maxCellZ = 0;          // largest |z| of a cell's solid-angle estimate
  double maxAlbedoZ = 0;        // largest |z| of sampled vs cosine albedo over the configurations
  bool chi2Run = false;         // the file defines pdfBRDF; the fields below are then set
  double minChi2PValue = 1;     // smallest p-value over the configurations (0: a test could not run, see chi2Failure)
  std::vector<double> chi2PValues;  // per configuration (in `configs` order) when run
  double chi2Threshold = 0;         // per-configuration significance: 0.01, Sidak-corrected over the configurations
  double maxPdfMismatch = 0;        // max relative |returned pdf - pdfBRDF(L, V)| over accepted samples
  std::string chi2Failure;          // why a configuration's test failed outright (a sample where
                                    // pdfBRDF integrates to 0, a bad expected count); empty otherwise
  double maxLengthError = 0;        // max | |L| - 1 | over draws with pdf > 0
  uint64_t pdfBelowHorizon = 0;     // draws with pdf > 0 and N.L <= 0
  uint32_t configurations = 0;
  uint64_t samplesPerConfiguration = 0;
  std::vector<SamplerConfigResult> configs;
  // The configuration whose check is nearest to (or furthest past) its limit, with zLimit 5:
  // an index into `configs`, the check's name and value, and a sentence naming all three.
  size_t worstConfig = 0;
  std::string worstCheck;
  double worstValue = 0, worstSeverity = 0;
  std::string worst;  // "normal near +z (1e-3 rad) (..), view 60 deg at azimuth 45 deg: length 4.3e-04 (limit 1e-04)"
  double ms = 0;      // wall time of the check

  static constexpr double kValueLimit = 1e-3, kPdfLimit = 1e-3, kLengthLimit = 1e-4;
  bool chi2Passed() const { return !chi2Run || (minChi2PValue >= chi2Threshold && maxPdfMismatch < kPdfLimit); }
  bool passed(double zLimit = 5.0) const {
    return maxValueMismatch < kValueLimit && maxCellZ < zLimit && maxAlbedoZ < zLimit && chi2Passed() &&
           maxLengthError < kLengthLimit && pdfBelowHorizon == 0;
  }
};

// Checks of the environment sampler on the device, over 2^20 independent draws:
//  - the cells drawn against the probabilities the alias table realises (Pearson chi-square over
//    blocks of 4 x 4 cells, small blocks pooled), and the positions inside the cells against
//    uniform (chi-square over 8 x 8 sub-cells): together, the draws follow the distribution;
//  - the pdf the sampler returns as the density in solid angle of its draws, with no
//    quadrature: over 20 x 40 equal-area (cos theta, phi) bins, the mean of 1_bin / pdf must
//    equal the bin's solid angle (z-scores, over bins with at least 64 draws whose densities
//    span at most a factor 8, where the error bar of that mean is reliable);
//  - that pdf against brdfa_environmentPdf(direction) on the device and the host's table;
//  - every direction of unit length.
// A constant environment (the furnace) has no table and is sampled uniformly: NotFound there.
struct EnvironmentSamplerReport {
  uint64_t samples = 0;
  double cellChi2PValue = 0;
  double positionChi2PValue = 0;
  double maxSolidAngleZ = 0;
  uint32_t solidAngleBins = 0;     // bins the z-scores covered
  double maxPdfMismatch = 0;       // largest relative |returned - brdfa_environmentPdf| (device)
  double hostPdfMismatch = 0;      // largest relative |returned - the host's EnvironmentDistribution::pdf|
  double pdfMismatchFraction = 0;  // draws off by more than 1e-3 (a cell edge rounded onto its neighbour)
  double maxLengthError = 0;
  std::string failure;  // why a chi-square test could not run
  bool passed(double alpha = 1e-3, double zLimit = 5.0) const {
    return failure.empty() && cellChi2PValue >= alpha && positionChi2PValue >= alpha && maxSolidAngleZ < zLimit &&
           pdfMismatchFraction < 1e-3 && maxLengthError < 1e-5;
  }
};

// Analysis of one BRDF on the device: the file's own compiled BRDF() (legacy
// render() files are Unsupported), in the frame N = +z, X = +x, Y = +y. A setting maps
// parameter names to values; names it leaves out take the file's defaults.
using ParamSetting = std::map<std::string, Vec3>;
struct DirectionPair {
  Vec3 light{0, 0, 1};  // L, unit
  Vec3 view{0, 0, 1};   // V, unit
};
// Directional albedo E(V) = integral of f(L, V) (N.L) dL, per channel, with the standard error
// of the estimate: the file's sampleBRDF() where it has one (importance sampling), else a
// cosine + log-polar half-vector mixture that resolves lobes down to 1e-6 rad
// (shaders/lib/albedo.glsl); the error is the spread of independent randomised replicates.
struct AlbedoEstimate {
  Vec3 mean{0, 0, 0};
  Vec3 stdError{0, 0, 0};
  uint64_t samples = 0;    // evaluations behind the estimate
  uint64_t nonFinite = 0;  // NaN or Inf values of f cos / pdf, left out of the mean
};
const char* albedoEstimatorName(const BrdfDefinition& brdf);  // "brdf sampler" | "cosine + half-vector mixture"

class Renderer {
 public:
  virtual ~Renderer() = default;

  // Opens the Vulkan device: options.deviceName when given, else a discrete or integrated GPU
  // when one exists, else a CPU device (lavapipe).
  static Result<std::shared_ptr<Renderer>> create(const RendererOptions& options);

  virtual const DeviceInfo& device() const = 0;

  // Compiles the BRDF's shading kernel without rendering (validation). Thread-safe.
  virtual Result<CompileInfo> compileBrdf(const BrdfDefinition& brdf) = 0;

  virtual Result<std::unique_ptr<RenderView>> createView() = 0;

  // Runs the numeric checks above. Thread-safe; compiles the BRDF (CompileError on failure).
  virtual Result<BrdfCheckReport> checkBrdf(const BrdfDefinition& brdf) = 0;

  // Runs the sampler checks above; InvalidArgument when the file has no sample section.
  virtual Result<SamplerCheckReport> checkSampler(const BrdfDefinition& brdf) = 0;

  // f(L, V) at every pair, for every setting: values[s * pairs.size() + p] (Analysis above).
  // Thread-safe; compiles the BRDF's analysis kernel (CompileError on failure).
  virtual Result<std::vector<Vec3>> evaluateBrdf(const BrdfDefinition& brdf, const std::vector<ParamSetting>& settings,
                                                 const std::vector<DirectionPair>& pairs) = 0;

  // The directional albedo at every view (unit, N.V > 0), for every setting, from about
  // samplesPerView samples each (rounded up to whole replicates of 1024): out[s * views.size() + v].
  virtual Result<std::vector<AlbedoEstimate>> estimateAlbedo(const BrdfDefinition& brdf,
                                                             const std::vector<ParamSetting>& settings,
                                                             const std::vector<Vec3>& views,
                                                             uint32_t samplesPerView) = 0;

  // Runs the environment sampler checks above on `environment` (a built-in or registered name).
  virtual Result<EnvironmentSamplerReport> checkEnvironmentSampler(const std::string& environment) = 0;

  // --hot-load (the BRDFA Engine's "hot start"): builds the shading pipelines of `brdf`, in every
  // sampling and environment variant, whose SPIR-V is already in the memory or disk cache;
  // never compiles GLSL. Returns how many pipelines it built (0 when none was cached or all
  // were already built). Thread-safe.
  virtual Result<int> preloadFromCache(const BrdfDefinition& brdf) = 0;

  virtual RendererCounters counters() const = 0;

  // For shutdown: every call in progress or made later fails promptly (DeviceError) instead of
  // waiting for the device. Only an isolated renderer can stop its device's work; an
  // in-process one lets calls in progress finish.
  virtual void cancel() {}

  // Makes the asset file at `path` usable in scenes under `name` (a mesh, texture or
  // environment name, by kind), beside the built-ins. The file should have passed inspectAsset
  // for `kind`; it is read, decoded and uploaded when a scene first uses it, then kept while
  // any view uses it. InvalidArgument when `name` is empty or a built-in's name of that kind.
  // Registering a name again replaces the file for later scenes. A measured table (kind
  // Measured, named by BrdfDefinition::measuredTable) is read and uploaded at once instead, and
  // kept: OverBudget when the memory budget cannot hold it (nothing is registered then), and
  // the file's errors (brdfa/measured.h's readMerl) as they are. Thread-safe.
  virtual Result<void> registerAsset(const std::string& name, AssetKind kind, const std::string& path) = 0;

  // Built-in names, then registered ones (sorted), of each kind.
  virtual std::vector<std::string> environmentNames() const = 0;
  virtual std::vector<std::string> meshNames() const = 0;
  virtual std::vector<std::string> textureNames() const = 0;
};

}  // namespace brdfa
