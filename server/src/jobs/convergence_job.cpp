#include "jobs/convergence_job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <set>

namespace brdfa::server {

namespace {

using json = nlohmann::json;

// The modes a request without "modes" compares: the hemisphere baseline, the BRDF's own
// sampler, the environment's, and their combination (the default).
const SamplingMode kDefaultModes[] = {SamplingMode::Cosine, SamplingMode::Brdf, SamplingMode::Environment,
                                      SamplingMode::Mis};

Error invalid(const std::string& field, const std::string& message) {
  return makeError(ErrorCode::InvalidArgument, field + ": " + message, field);
}

// An integer in [lo, hi] (300 or 300.0, never 300.5).
Result<int> readMs(const json& v, const std::string& field, int lo, int hi) {
  const std::string range =
      "an integer number of milliseconds in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  if (!v.is_number()) return invalid(field, "expected " + range + ", got " + v.type_name());
  const double d = v.get<double>();
  if (!std::isfinite(d) || d != std::floor(d) || d < lo || d > hi)
    return invalid(field, "must be " + range + ", got " + v.dump());
  return static_cast<int>(d);
}

double luminance(const float* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

json optionalNumber(const std::optional<double>& v) { return v && std::isfinite(*v) ? json(*v) : json(nullptr); }

Error cancelledError() { return makeError(ErrorCode::Internal, "cancelled"); }

}  // namespace

Result<ConvergenceJobSpec> parseConvergenceJob(const json& body, const SceneResolver& resolver) {
  if (!body.is_object())
    return makeError(ErrorCode::InvalidArgument,
                     "the body is {\"scene\": {...}, \"modes\": [...], \"time_ms\": N, \"reference_ms\": N}");
  for (auto it = body.begin(); it != body.end(); ++it)
    if (it.key() != "scene" && it.key() != "modes" && it.key() != "time_ms" && it.key() != "reference_ms")
      return invalid(it.key(), "unknown key (allowed: scene, modes, time_ms, reference_ms)");
  ConvergenceJobSpec spec;
  auto sceneIt = body.find("scene");
  if (sceneIt == body.end()) return invalid("scene", "required (a scene JSON object)");
  if (!sceneIt->is_object()) return invalid("scene", std::string("expected an object, got ") + sceneIt->type_name());
  Result<Scene> scene = sceneFromJson(*sceneIt, resolver);
  if (!scene) {
    // Field names inside the scene get the request's prefix ("scene.render.width").
    Error e = scene.takeError();
    if (!e.field.empty()) e.field = "scene." + e.field;
    e.message = "scene." + e.message;
    return e;
  }
  spec.scene = std::move(scene.value());
  if (static_cast<long long>(spec.scene.render.width) * spec.scene.render.height > kConvergenceMaxPixels)
    return invalid("scene.render", "a comparison renders at most " + std::to_string(kConvergenceMaxPixels) +
                                       " pixels (e.g. 1024x1024), got " + std::to_string(spec.scene.render.width) +
                                       "x" + std::to_string(spec.scene.render.height));
  spec.sceneJson = sceneToJson(spec.scene);

  if (auto it = body.find("modes"); it != body.end()) {
    if (!it->is_array() || it->empty() || it->size() > 5)
      return invalid("modes", "expected an array of 1 to 5 sampling modes (" + std::string(kSamplingChoices) + ")");
    std::set<std::string> seen;
    for (size_t i = 0; i < it->size(); ++i) {
      const std::string field = "modes[" + std::to_string(i) + "]";
      const json& m = (*it)[i];
      SamplingMode mode{};
      if (!m.is_string() || !samplingModeFromName(m.get<std::string>(), mode))
        return invalid(field, std::string("must be ") + kSamplingChoices + ", got " + m.dump());
      if (!seen.insert(m.get<std::string>()).second)
        return invalid(field, "\"" + m.get<std::string>() + "\" is listed twice");
      spec.modes.push_back(mode);
    }
  } else {
    spec.modes.assign(std::begin(kDefaultModes), std::end(kDefaultModes));
  }
  if (auto it = body.find("time_ms"); it != body.end()) {
    BRDFA_TRY_ASSIGN(int ms, readMs(*it, "time_ms", kConvergenceMinMs, kConvergenceMaxMs));
    spec.timeMs = ms;
  }
  spec.referenceMs = std::min(4 * spec.timeMs, kConvergenceMaxReferenceMs);
  if (auto it = body.find("reference_ms"); it != body.end()) {
    BRDFA_TRY_ASSIGN(int ms, readMs(*it, "reference_ms", kConvergenceMinMs, kConvergenceMaxReferenceMs));
    spec.referenceMs = ms;
  }
  return spec;
}

json convergenceJobRequestJson(const ConvergenceJobSpec& spec) {
  json modes = json::array();
  for (SamplingMode m : spec.modes) modes.push_back(samplingModeName(m));
  return {{"modes", modes}, {"time_ms", spec.timeMs}, {"reference_ms", spec.referenceMs}, {"scene", spec.sceneJson}};
}

std::optional<double> trueRelError(const std::vector<float>& rgba, const std::vector<float>& ref, double refRelError,
                                   double* meanRefLum, size_t* pixels, double* raw) {
  const size_t n = std::min(rgba.size(), ref.size()) / 4;
  double sumRef = 0, sumSq = 0;
  size_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    const double r = luminance(&ref[4 * i]);
    if (!(r > 0) || !std::isfinite(r)) continue;
    const double d = luminance(&rgba[4 * i]) - r;
    sumRef += r;
    sumSq += d * d;
    ++count;
  }
  if (meanRefLum) *meanRefLum = count ? sumRef / static_cast<double>(count) : 0;
  if (pixels) *pixels = count;
  if (count == 0) return std::nullopt;
  const double mean = sumRef / static_cast<double>(count);
  if (raw) *raw = std::sqrt(sumSq / static_cast<double>(count)) / mean;
  const double refVariance = refRelError * refRelError * mean * mean;
  const double mse = sumSq / static_cast<double>(count) - refVariance;
  const double e = std::sqrt(std::max(0.0, mse)) / mean;
  if (!std::isfinite(e)) return std::nullopt;
  return e;
}

namespace {

// The scene every timed view starts from: no visible environment, no stopping rule, and small
// enough passes that checkpoints are met closely.
Scene convergenceBaseScene(const ConvergenceJobSpec& spec) {
  Scene base = spec.scene;
  base.environment.visible = false;
  base.render.maxSamples = kMaxTotalSamples;
  base.render.targetError = 0;
  const int pixels = base.render.width * base.render.height;
  base.render.samplesPerFrame =
      std::clamp(kConvergenceSamplesPerPass / std::max(pixels, 1), 1, base.render.samplesPerFrame);
  return base;
}

Scene withSampling(const Scene& base, SamplingMode mode) {
  Scene s = base;
  s.render.sampling = mode;
  return s;
}

// Warm-up: build (and JIT) every program on a tiny view, so no timed pass pays for it.
Result<void> warmUpPrograms(Renderer& renderer, const ConvergenceJobSpec& spec, const Scene& base,
                            JobContext& context) {
  BRDFA_TRY_ASSIGN(std::unique_ptr<RenderView> warm, renderer.createView());
  std::vector<SamplingMode> all = spec.modes;
  if (std::find(all.begin(), all.end(), SamplingMode::Mis) == all.end()) all.push_back(SamplingMode::Mis);
  for (SamplingMode mode : all) {
    if (context.cancelled()) return cancelledError();
    Scene s = withSampling(base, mode);
    s.render.width = s.render.height = kMinImageSize;
    s.render.samplesPerFrame = 1;
    BRDFA_TRY(warm->setScene(s));
    BRDFA_TRY(warm->renderPass());
  }
  return {};
}

// The shared reference, in "mis", with a seed of its own: the "mis" run must share no sample
// with it, or its error against the reference would read too small.
Result<Frame> renderReference(Renderer& renderer, const ConvergenceJobSpec& spec, const Scene& base, double budget,
                              JobContext& context) {
  BRDFA_TRY_ASSIGN(std::unique_ptr<RenderView> view, renderer.createView());
  RenderView& v = *view;
  Scene referenceScene = withSampling(base, SamplingMode::Mis);
  referenceScene.render.seed ^= 0x9e3779b9u;
  BRDFA_TRY(v.setScene(referenceScene));
  for (;;) {
    if (context.cancelled()) return cancelledError();
    BRDFA_TRY_ASSIGN(FrameStats pass, v.renderPass());
    context.setProgress(std::min(pass.elapsedMs, double(spec.referenceMs)) / budget);
    if (pass.elapsedMs >= spec.referenceMs || pass.done()) break;
  }
  return v.readFrame(true);
}

// One timed view per compared mode.
struct Run {
  SamplingMode mode;
  std::unique_ptr<RenderView> view;
  FrameStats stats;
  bool done = false;
  json curve = json::array();
  json last;  // the latest checkpoint
};

Result<std::vector<Run>> startRuns(Renderer& renderer, const ConvergenceJobSpec& spec, const Scene& base) {
  std::vector<Run> runs;
  for (SamplingMode mode : spec.modes) {
    BRDFA_TRY_ASSIGN(std::unique_ptr<RenderView> view, renderer.createView());
    BRDFA_TRY(view->setScene(withSampling(base, mode)));
    Run run{mode, std::move(view), {}, false, json::array(), nullptr};
    run.stats = run.view->stats();
    runs.push_back(std::move(run));
  }
  return runs;
}

// Checkpoints evenly spaced in log-time over [time_ms / 64, time_ms].
std::vector<double> checkpointTimes(const ConvergenceJobSpec& spec) {
  std::vector<double> checkpoints(kConvergenceCheckpoints);
  for (int k = 0; k < kConvergenceCheckpoints; ++k)
    checkpoints[k] =
        spec.timeMs * std::pow(64.0, double(k - (kConvergenceCheckpoints - 1)) / (kConvergenceCheckpoints - 1));
  checkpoints.back() = spec.timeMs;
  return checkpoints;
}

// Reads every run's frame and adds its point against the reference.
Result<void> recordCheckpoint(std::vector<Run>& runs, const Frame& reference, double refRelError) {
  for (Run& run : runs) {
    BRDFA_TRY_ASSIGN(Frame frame, run.view->readFrame(true));
    const FrameStats& st = frame.stats;
    double raw = 0;
    std::optional<double> truth = trueRelError(frame.rgba32f, reference.rgba32f, refRelError, nullptr, nullptr, &raw);
    json point{{"elapsed_ms", st.elapsedMs},
               {"spp", st.spp},
               {"passes", st.passes},
               {"rel_error", optionalNumber(st.relError)},
               {"true_rel_error", optionalNumber(truth)},
               {"raw_rel_error", truth ? json(raw) : json(nullptr)}};
    run.stats = st;
    // Several checkpoints passed by one long pass give one point.
    if (run.curve.empty() || run.curve.back()["spp"] != st.spp) run.curve.push_back(point);
    run.last = point;
  }
  return {};
}

// Renders the slowest unfinished run one pass at a time, recording every checkpoint all runs
// have passed, until the last checkpoint.
Result<void> runToCheckpoints(std::vector<Run>& runs, const std::vector<double>& checkpoints,
                              const ConvergenceJobSpec& spec, const Frame& reference, double refRelError, double spent,
                              double budget, JobContext& context) {
  size_t next = 0;
  while (next < checkpoints.size()) {
    if (context.cancelled()) return cancelledError();
    Run* slowest = nullptr;
    for (Run& run : runs)
      if (!run.done && run.stats.elapsedMs < spec.timeMs &&
          (!slowest || run.stats.elapsedMs < slowest->stats.elapsedMs))
        slowest = &run;
    double reached = std::numeric_limits<double>::infinity();
    for (const Run& run : runs)
      if (!run.done) reached = std::min(reached, run.stats.elapsedMs);
    if (!slowest || reached >= checkpoints[next]) {
      while (next < checkpoints.size() && (!slowest || reached >= checkpoints[next])) ++next;
      BRDFA_TRY(recordCheckpoint(runs, reference, refRelError));
      continue;
    }
    BRDFA_TRY_ASSIGN(FrameStats pass, slowest->view->renderPass());
    slowest->stats = pass;
    slowest->done = pass.done();
    double progress = spent;
    for (const Run& run : runs) progress += std::min(run.stats.elapsedMs, double(spec.timeMs));
    context.setProgress(std::min(0.99, progress / budget));
  }
  return {};
}

// Equal-time comparison at the last checkpoint: each mode's entry, its relMSE against the
// cosine run's, and the best mode.
struct Comparison {
  json modes = json::array();
  json ratios;
  json best;
};

Comparison compareRuns(const std::vector<Run>& runs) {
  auto relmse = [](const json& point) -> std::optional<double> {
    if (!point.is_object() || !point["true_rel_error"].is_number()) return std::nullopt;
    const double e = point["true_rel_error"].get<double>();
    return e * e;
  };
  std::optional<double> cosineMse;
  for (const Run& run : runs)
    if (run.mode == SamplingMode::Cosine) cosineMse = relmse(run.last);
  const bool haveCosine =
      std::any_of(runs.begin(), runs.end(), [](const Run& r) { return r.mode == SamplingMode::Cosine; });
  Comparison out;
  out.ratios = haveCosine ? json::object() : json(nullptr);
  out.best = nullptr;
  double bestMse = std::numeric_limits<double>::infinity();
  for (const Run& run : runs) {
    const char* name = samplingModeName(run.mode);
    std::optional<double> mse = relmse(run.last);
    json final = run.last;
    if (final.is_object()) final["relmse"] = optionalNumber(mse);
    json ratio = nullptr;
    if (cosineMse && mse && *mse > 0) ratio = *cosineMse / *mse;
    if (haveCosine) out.ratios[name] = ratio;
    if (mse && *mse < bestMse) {
      bestMse = *mse;
      out.best = name;
    }
    out.modes.push_back({{"sampling", name},
                         {"estimator", run.stats.estimator},
                         {"warnings", run.stats.warnings},
                         {"curve", run.curve},
                         {"final", final},
                         {"equal_time_relmse_vs_cosine", ratio}});
  }
  return out;
}

}  // namespace

Result<json> runConvergenceJob(Renderer& renderer, const ConvergenceJobSpec& spec, JobContext& context) {
  const Scene base = convergenceBaseScene(spec);
  const double budget = static_cast<double>(spec.referenceMs) + static_cast<double>(spec.timeMs) * spec.modes.size();
  BRDFA_TRY(warmUpPrograms(renderer, spec, base, context));
  BRDFA_TRY_ASSIGN(Frame referenceFrame, renderReference(renderer, spec, base, budget, context));
  const Frame reference = std::move(referenceFrame);
  const double spent = spec.referenceMs;  // render ms of finished phases, for progress
  const double refRelError = reference.stats.relError.value_or(0.0);
  double refMeanLum = 0;
  size_t refPixels = 0;
  trueRelError(reference.rgba32f, reference.rgba32f, 0, &refMeanLum, &refPixels);

  BRDFA_TRY_ASSIGN(std::vector<Run> started, startRuns(renderer, spec, base));
  std::vector<Run> runs = std::move(started);
  const std::vector<double> checkpoints = checkpointTimes(spec);
  BRDFA_TRY(runToCheckpoints(runs, checkpoints, spec, reference, refRelError, spent, budget, context));

  Comparison comparison = compareRuns(runs);
  return json{{"time_ms", spec.timeMs},
              {"reference_ms", spec.referenceMs},
              {"width", base.render.width},
              {"height", base.render.height},
              {"checkpoints_ms", checkpoints},
              {"reference",
               {{"sampling", samplingModeName(SamplingMode::Mis)},
                {"estimator", reference.stats.estimator},
                {"elapsed_ms", reference.stats.elapsedMs},
                {"spp", reference.stats.spp},
                {"rel_error", optionalNumber(reference.stats.relError)},
                {"mean_luminance", refMeanLum},
                {"pixels", refPixels}}},
              {"modes", comparison.modes},
              {"equal_time_relmse_vs_cosine", comparison.ratios},
              {"best", comparison.best}};
}

}  // namespace brdfa::server
