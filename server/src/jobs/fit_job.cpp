// runFitJob and sourceWithDefaults (fit_job.h): the optimisation behind POST /api/jobs/fit.
#include "jobs/fit_job.h"

#include <nlopt.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

#include "brdfa/measured.h"
#include "json/brdf_json.h"
#include "util/auth_crypto.h"

namespace brdfa::server {

namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

Error cancelledError() { return makeError(ErrorCode::Internal, "cancelled"); }

// One scalar the optimiser moves: a component of a fitted parameter, scaled to [0, 1].
struct Variable {
  std::string param;
  int component = 0;
  double lo = 0, hi = 1;
};

std::vector<Variable> variablesOf(const FitJobSpec& spec) {
  std::vector<Variable> out;
  for (const FitParam& p : spec.fit)
    for (int c = 0; c < (p.type == ParamType::Color ? 3 : 1); ++c) out.push_back(Variable{p.name, c, p.lo, p.hi});
  return out;
}

ParamSetting settingAt(const FitJobSpec& spec, const std::vector<Variable>& vars, const double* x) {
  ParamSetting s = spec.start;
  for (size_t i = 0; i < vars.size(); ++i)
    s[vars[i].param][vars[i].component] = float(vars[i].lo + std::clamp(x[i], 0.0, 1.0) * (vars[i].hi - vars[i].lo));
  return s;
}

// The radical inverse of `index` in `base`: Halton points spread the restarts' starts.
double radicalInverse(unsigned index, unsigned base) {
  double inv = 1.0 / base, f = inv, out = 0;
  for (; index > 0; index /= base, f *= inv) out += f * double(index % base);
  return out;
}

// Restart 0 starts at the model's values, restart r > 0 at Halton point r kept off the bounds.
std::vector<double> startPoint(const FitJobSpec& spec, const std::vector<Variable>& vars, int restart) {
  static const unsigned kPrimes[kFitMaxVariables] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37};
  std::vector<double> x(vars.size());
  for (size_t i = 0; i < vars.size(); ++i) {
    if (restart == 0) {
      const double v = spec.start.at(vars[i].param)[vars[i].component];
      x[i] = std::clamp((v - vars[i].lo) / (vars[i].hi - vars[i].lo), 0.0, 1.0);
    } else {
      x[i] = 0.05 + 0.9 * radicalInverse(unsigned(restart), kPrimes[i]);
    }
  }
  return x;
}

// Everything the objective needs and records, across restarts.
struct FitState {
  Renderer& renderer;
  const FitJobSpec& spec;
  const FitBins& bins;
  const std::vector<Variable>& vars;
  JobContext& context;
  Clock::time_point deadline;
  nlopt_opt opt = nullptr;  // the restart running now
  int restart = 0;
  int restartEvaluations = 0;
  std::optional<Error> error;
  struct Point {
    int evaluation, restart;
    double loss, best;
  };
  std::vector<Point> curve;
  double best = HUGE_VAL;
  std::vector<double> bestX;
  double restartBest = HUGE_VAL;
  std::vector<double> restartBestX;
};

json curveJson(const std::vector<FitState::Point>& curve) {
  json out = json::array();
  const size_t n = curve.size(), keep = std::min(n, kFitCurvePoints);
  for (size_t k = 0; k < keep; ++k) {
    const FitState::Point& p = curve[keep == n ? k : (k * (n - 1)) / (keep - 1)];
    out.push_back({{"evaluation", p.evaluation}, {"loss", p.loss}, {"best", p.best}, {"restart", p.restart}});
  }
  return out;
}

double objective(unsigned n, const double* x, double* /*grad: derivative-free*/, void* data) {
  FitState& s = *static_cast<FitState*>(data);
  if (s.context.cancelled() || Clock::now() > s.deadline || s.error) {
    nlopt_force_stop(s.opt);
    return HUGE_VAL;
  }
  Result<std::vector<Vec3>> values =
      s.renderer.evaluateBrdf(*s.spec.model->definition, {settingAt(s.spec, s.vars, x)}, s.bins.pairs);
  if (!values) {
    s.error = values.takeError();
    nlopt_force_stop(s.opt);
    return HUGE_VAL;
  }
  const double loss = fitLossValue(s.spec.loss, s.bins, values.value());
  ++s.restartEvaluations;
  if (loss < s.restartBest) {
    s.restartBest = loss;
    s.restartBestX.assign(x, x + n);
  }
  if (loss < s.best) {
    s.best = loss;
    s.bestX.assign(x, x + n);
  }
  s.curve.push_back({int(s.curve.size()) + 1, s.restart, loss, s.best});
  s.context.setProgress(0.95 * double(s.curve.size()) / s.spec.maxEvaluations);
  if (s.curve.size() % 8 == 0) s.context.setPartial({{"loss_curve", curveJson(s.curve)}, {"best_loss", s.best}});
  return loss;
}

json paramsJson(const BrdfDefinition& def, const ParamSetting& setting) {
  json out = json::object();
  for (const BrdfParam& p : def.params) out[p.name] = paramValueToJson(p.type, setting.at(p.name));
  return out;
}

// One restart from `x`: NLopt's result code, the restart's best point in `x`.
nlopt_result runRestart(FitState& s, std::vector<double>& x, int evaluations) {
  const unsigned n = unsigned(x.size());
  // BOBYQA needs at least two variables.
  s.opt = nlopt_create(n >= 2 ? NLOPT_LN_BOBYQA : NLOPT_LN_SBPLX, n);
  if (!s.opt) return NLOPT_OUT_OF_MEMORY;
  const std::vector<double> lower(n, 0.0), upper(n, 1.0), step(n, 0.1);
  nlopt_set_lower_bounds(s.opt, lower.data());
  nlopt_set_upper_bounds(s.opt, upper.data());
  nlopt_set_min_objective(s.opt, objective, &s);
  nlopt_set_initial_step(s.opt, step.data());
  nlopt_set_maxeval(s.opt, evaluations);
  nlopt_set_xtol_abs1(s.opt, 1e-7);  // of the [0, 1] range: far below any parameter's meaning
  nlopt_set_ftol_rel(s.opt, 1e-12);  // the loss is float32 sums: stop at its noise
  s.restartBest = HUGE_VAL;
  s.restartEvaluations = 0;
  double value = 0;
  const nlopt_result r = nlopt_optimize(s.opt, x.data(), &value);
  nlopt_destroy(s.opt);
  s.opt = nullptr;
  if (!s.restartBestX.empty() && s.restartBest < HUGE_VAL) x = s.restartBestX;
  return r;
}

const char* resultName(nlopt_result r) {
  switch (r) {
    case NLOPT_SUCCESS: return "converged";
    case NLOPT_FTOL_REACHED: return "loss tolerance reached";
    case NLOPT_XTOL_REACHED: return "parameter tolerance reached";
    case NLOPT_MAXEVAL_REACHED: return "evaluation budget spent";
    case NLOPT_MAXTIME_REACHED: return "time limit";
    case NLOPT_FORCED_STOP: return "stopped";
    case NLOPT_ROUNDOFF_LIMITED: return "round-off limited";
    default: return "failed";
  }
}

Result<std::string> readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(ErrorCode::NotFound, "the measured table file cannot be opened", "target.brdf");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The target's values at `bins`, keeping the bins where it has them.
Result<FitBins> withTarget(Renderer& renderer, const FitJobSpec& spec, FitBins bins,
                           const std::shared_ptr<MeasuredTable>& table) {
  if (table) return withMeasuredTarget(std::move(bins), *table);
  BRDFA_TRY_ASSIGN(std::vector<Vec3> values, renderer.evaluateBrdf(*spec.target, {spec.targetParams}, bins.pairs));
  return withEvaluatedTarget(std::move(bins), values);
}

// The residual slice at the fitted values: numbers and the PNG as a data URL.
Result<json> residualJson(Renderer& renderer, const FitJobSpec& spec, const FitBins& slice,
                          const ParamSetting& fitted) {
  BRDFA_TRY_ASSIGN(std::vector<Vec3> model, renderer.evaluateBrdf(*spec.model->definition, {fitted}, slice.pairs));
  ResidualSlice r = residualSlice(spec.loss, slice, model);
  json values = json::array();
  for (const auto& v : r.values) values.push_back(v ? json(*v) : json(nullptr));
  const std::vector<uint8_t> png = residualPng(r);
  const double phiD = (kResidualPhiDBin + 0.5) * 180.0 / kMerlPhiDBins;
  return json{{"phi_d_bin", kResidualPhiDBin},
              {"phi_d_deg", phiD},
              {"theta_h_bins", kMerlThetaHBins},
              {"theta_d_bins", kMerlThetaDBins},
              {"max_abs", r.maxAbs},
              {"values", values},
              {"png", "data:image/png;base64," + base64Encode(std::string(png.begin(), png.end()))}};
}

// A preset name from the target's: [A-Za-z0-9_-], at most 64 characters.
std::string presetName(const std::string& target) {
  std::string out = "fit_";
  for (char c : target)
    if (out.size() < 64) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : '_';
  return out;
}

}  // namespace

std::string sourceWithDefaults(const std::string& source, const BrdfDefinition& brdf, const ParamSetting& values) {
  std::vector<std::string> lines;
  std::istringstream in(source);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  for (const BrdfParam& p : brdf.params) {
    auto v = values.find(p.name);
    if (v == values.end() || p.line < 1 || size_t(p.line) > lines.size()) continue;
    std::string& line = lines[size_t(p.line) - 1];
    const size_t hash = line.find('#');
    const std::string comment = hash == std::string::npos ? "" : "    " + line.substr(hash);
    std::ostringstream out;
    out.precision(6);
    if (p.type == ParamType::Float)
      out << "float " << p.name << ' ' << p.min << ' ' << p.max << ' ' << v->second[0];
    else if (p.type == ParamType::Color)
      out << "color " << p.name << ' ' << v->second[0] << ' ' << v->second[1] << ' ' << v->second[2];
    else
      out << "bool " << p.name << ' ' << (v->second[0] != 0 ? 1 : 0);
    line = out.str() + comment;
  }
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

Result<json> runFitJob(Renderer& renderer, const FitJobSpec& spec, JobContext& context) {
  std::shared_ptr<MeasuredTable> table;
  if (!spec.measuredPath.empty()) {
    BRDFA_TRY_ASSIGN(std::string bytes, readFile(spec.measuredPath));
    BRDFA_TRY_ASSIGN(MeasuredTable read, readMerl(bytes));
    table = std::make_shared<MeasuredTable>(std::move(read));
  }
  BRDFA_TRY_ASSIGN(FitBins bins, withTarget(renderer, spec, fitGridBins(), table));
  BRDFA_TRY_ASSIGN(FitBins slice, withTarget(renderer, spec, residualSliceBins(), table));
  table.reset();
  if (bins.bins.empty())
    return makeError(ErrorCode::InvalidArgument, "target: '" + spec.targetName + "' has no value in any bin of the fit",
                     "target.brdf");

  const std::vector<Variable> vars = variablesOf(spec);
  FitState s{renderer,
             spec,
             bins,
             vars,
             context,
             Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kFitMaxSeconds))};
  json restarts = json::array();
  for (int r = 0; r < spec.restarts; ++r) {
    const int left = spec.maxEvaluations - int(s.curve.size());
    if (left < 2 || context.cancelled() || Clock::now() > s.deadline) break;
    s.restart = r;
    std::vector<double> x = startPoint(spec, vars, r);
    const json start = paramsJson(*spec.model->definition, settingAt(spec, vars, x.data()));
    const nlopt_result result = runRestart(s, x, left / (spec.restarts - r));
    if (s.error) return *s.error;
    if (context.cancelled()) return cancelledError();
    restarts.push_back({{"start", start},
                        {"params", paramsJson(*spec.model->definition, settingAt(spec, vars, x.data()))},
                        {"loss", s.restartBest < HUGE_VAL ? json(s.restartBest) : json(nullptr)},
                        {"evaluations", s.restartEvaluations},
                        {"stopped_by", resultName(result)}});
  }
  if (s.bestX.empty()) return makeError(ErrorCode::Internal, "the fit made no evaluation");
  const ParamSetting fitted = settingAt(spec, vars, s.bestX.data());
  BRDFA_TRY_ASSIGN(json residual, residualJson(renderer, spec, slice, fitted));
  json fittedNames = json::array();
  for (const FitParam& p : spec.fit) fittedNames.push_back(p.name);
  const json params = paramsJson(*spec.model->definition, fitted);
  return json{{"model", spec.modelName},
              {"target", spec.targetName},
              {"loss", fitLossName(spec.loss)},
              {"params", params},
              {"fitted", fittedNames},
              {"final_loss", s.best},
              {"initial_loss", s.curve.front().loss},
              {"loss_curve", curveJson(s.curve)},
              {"restarts", restarts},
              {"evaluations", s.curve.size()},
              {"bins", bins.bins.size()},
              {"residual", residual},
              {"preset", {{"brdf", spec.modelName}, {"name", presetName(spec.targetName)}, {"values", params}}},
              {"brdf_source", sourceWithDefaults(spec.model->source, *spec.model->definition, fitted)}};
}

}  // namespace brdfa::server
