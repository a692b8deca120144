// POST /api/jobs/fit: fits some parameters of a model BRDF (any .brdf with a BRDF()) to a target,
// a measured upload or another BRDF at given parameters, and returns the fitted parameters, the
// loss curve, the residual over one slice of bins and a ready preset.
//
// How it fits:
// - The bins, the target's values there and the loss are fit_loss.h's. A measured target's
//   values are its table's own bins; a BRDF target is evaluated once on the device.
// - Each loss evaluation runs the model's own compiled BRDF() on the device
//   (Renderer::evaluateBrdf) at every kept bin.
// - The optimiser is NLopt's BOBYQA (Powell's bound-constrained quadratic model method; Subplex
//   for a single variable, which BOBYQA does not take), over the fitted components (a float
//   parameter is one, a color three) scaled to [0, 1] within their bounds. Restart 0 starts
//   from the model's values (its defaults, or "params"), the others from Halton points inside
//   the bounds; the best result of all restarts wins. The evaluations are shared out evenly
//   over the restarts still to run, and all stop at kFitMaxSeconds.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "brdfa/renderer.h"
#include "jobs/fit_loss.h"
#include "jobs/jobs.h"
#include "storage/brdf_library.h"

namespace brdfa::server {

inline constexpr int kFitMaxRestarts = 16;
inline constexpr int kFitDefaultRestarts = 4;
inline constexpr int kFitMinEvaluations = 20;
inline constexpr int kFitMaxEvaluations = 20000;
inline constexpr int kFitDefaultEvaluations = 2000;
inline constexpr int kFitMaxVariables = 12;
inline constexpr double kFitMaxSeconds = 600;
inline constexpr size_t kFitCurvePoints = 512;  // the loss curve is thinned to at most this

// One fitted parameter: its bounds apply to each of its components (float, as the values).
struct FitParam {
  std::string name;
  ParamType type = ParamType::Float;
  float lo = 0, hi = 1;
};

struct FitJobSpec {
  std::string modelName;
  std::shared_ptr<const BrdfEntry> model;
  ParamSetting start;  // every model parameter: defaults, or the request's "params"
  std::vector<FitParam> fit;
  std::string targetName;
  std::shared_ptr<const BrdfDefinition> target;
  ParamSetting targetParams;
  std::string measuredPath;  // the stored table of a measured target, else empty
  FitLoss loss = FitLoss::Log;
  int restarts = kFitDefaultRestarts;
  int maxEvaluations = kFitDefaultEvaluations;
  std::vector<std::string> notes;  // values clamped into their ranges
};

// How the parser finds names: a BRDF the requester may read (null: unknown to them), and the
// stored file of a measured upload (nullopt: none).
struct FitLookup {
  std::function<std::shared_ptr<const BrdfEntry>(const std::string&)> brdf;
  std::function<std::optional<std::string>(const std::string&)> measuredPath;
};

// {"model": {"brdf", "fit": {name: [lo, hi] | null}, "params"}, "target": {"brdf", "params"},
// "loss", "restarts", "max_evaluations"} (docs/api.md). InvalidArgument (400) naming the field,
// NotFound (404) for a BRDF name the requester cannot read.
Result<FitJobSpec> parseFitJob(const nlohmann::json& body, const FitLookup& lookup);

// What describe() echoes as "request".
nlohmann::json fitJobRequestJson(const FitJobSpec& spec);

// Runs the fit; the result JSON is documented in docs/api.md. Returns early (an Error the job
// manager drops) when `context` is cancelled.
Result<nlohmann::json> runFitJob(Renderer& renderer, const FitJobSpec& spec, JobContext& context);

// `source` (a .brdf text) with the default values of the parameters in `values` replaced, each
// on its own line (BrdfParam::line); comments and every other line unchanged.
std::string sourceWithDefaults(const std::string& source, const BrdfDefinition& brdf, const ParamSetting& values);

}  // namespace brdfa::server
