// parseFitJob and fitJobRequestJson (fit_job.h): the request of POST /api/jobs/fit.
#include <cmath>
#include <set>

#include "jobs/fit_job.h"
#include "json/brdf_json.h"
#include "json/json_numbers.h"
#include "json/scene_json.h"

namespace brdfa::server {

namespace {

using json = nlohmann::json;

Error invalid(const std::string& field, const std::string& message) {
  return makeError(ErrorCode::InvalidArgument, field + ": " + message, field);
}

Result<void> onlyKeys(const json& object, const std::string& field, std::initializer_list<const char*> keys) {
  std::string known;
  for (const char* k : keys) known += (known.empty() ? "" : ", ") + std::string(k);
  if (!object.is_object()) return invalid(field, "expected an object with " + known);
  for (auto it = object.begin(); it != object.end(); ++it) {
    bool ok = false;
    for (const char* k : keys) ok = ok || it.key() == k;
    if (!ok) return invalid(field.empty() ? it.key() : field + "." + it.key(), "unknown key (known: " + known + ")");
  }
  return {};
}

// An integer in [lo, hi].
Result<int> readCount(const json& body, const char* key, int lo, int hi, int fallback) {
  auto it = body.find(key);
  if (it == body.end()) return fallback;
  const std::string range = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  if (!it->is_number()) return invalid(key, "expected " + range);
  const double d = it->get<double>();
  if (!std::isfinite(d) || d != std::floor(d) || d < lo || d > hi) return invalid(key, "must be " + range);
  return int(d);
}

// {"brdf": name} resolved: the entry the requester may read.
Result<std::shared_ptr<const BrdfEntry>> readBrdfName(const json& part, const std::string& field,
                                                      const FitLookup& lookup) {
  auto name = part.find("brdf");
  if (name == part.end() || !name->is_string()) return invalid(field + ".brdf", "must name a BRDF");
  std::shared_ptr<const BrdfEntry> entry = lookup.brdf(name->get<std::string>());
  // Someone else's BRDF is as unknown as one that does not exist.
  if (!entry)
    return makeError(ErrorCode::NotFound, field + ".brdf: unknown BRDF '" + name->get<std::string>() + "'",
                     field + ".brdf");
  if (entry->definition->format != BrdfFormat::Explorer)
    return invalid(field + ".brdf", "'" + entry->name + "' is a legacy render() file: it has no BRDF() to evaluate");
  return entry;
}

// One entry of model.fit: [lo, hi] inside the parameter's range (a color's: [0, 1e6]), or null
// for the whole declared range (a color's: [0, 1]).
Result<FitParam> readFitParam(const BrdfDefinition& model, const std::string& modelName, const std::string& name,
                              const json& value, const std::string& field) {
  const BrdfParam* p = model.findParam(name);
  if (!p) return invalid(field, "BRDF '" + modelName + "' has no parameter '" + name + "'");
  if (p->type == ParamType::Bool)
    return invalid(field, "'" + name + "' is a bool: only float and color parameters fit");
  FitParam out{p->name, p->type, p->type == ParamType::Float ? p->min : 0.0f,
               p->type == ParamType::Float ? p->max : 1.0f};
  if (value.is_null()) return out;
  if (!value.is_array() || value.size() != 2 || !value[0].is_number() || !value[1].is_number())
    return invalid(field, "expected [min, max] or null (the declared range)");
  const double lo = value[0].get<double>(), hi = value[1].get<double>();
  const float allowedLo = p->type == ParamType::Float ? p->min : 0.0f;
  const float allowedHi = p->type == ParamType::Float ? p->max : 1e6f;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(float(lo) < float(hi)) || float(lo) < allowedLo ||
      float(hi) > allowedHi)
    return invalid(field, "bounds must satisfy " + json(floatForJson(allowedLo)).dump() +
                              " <= min < max <= " + json(floatForJson(allowedHi)).dump() + ", got " + value.dump());
  out.lo = float(lo);
  out.hi = float(hi);
  return out;
}

Result<void> readModel(const json& body, const FitLookup& lookup, FitJobSpec& spec) {
  auto it = body.find("model");
  if (it == body.end()) return invalid("model", "required: {\"brdf\": name, \"fit\": {parameter: [min, max]}}");
  BRDFA_TRY(onlyKeys(*it, "model", {"brdf", "fit", "params"}));
  BRDFA_TRY_ASSIGN(spec.model, readBrdfName(*it, "model", lookup));
  spec.modelName = spec.model->name;
  const BrdfDefinition& def = *spec.model->definition;
  const json* params = it->contains("params") ? &(*it)["params"] : nullptr;
  BRDFA_TRY_ASSIGN(spec.start, paramsFromJson(def, spec.modelName, params, "model.params", &spec.notes));
  auto fit = it->find("fit");
  if (fit == it->end() || !fit->is_object() || fit->empty())
    return invalid("model.fit", "required: an object of the parameters to fit, {name: [min, max] or null}");
  size_t variables = 0;
  for (auto f = fit->begin(); f != fit->end(); ++f) {
    BRDFA_TRY_ASSIGN(FitParam param, readFitParam(def, spec.modelName, f.key(), f.value(), "model.fit." + f.key()));
    variables += param.type == ParamType::Color ? 3 : 1;
    spec.fit.push_back(std::move(param));
  }
  if (variables > size_t(kFitMaxVariables))
    return invalid("model.fit", "at most " + std::to_string(kFitMaxVariables) +
                                    " values fit at once (a color is 3), got " + std::to_string(variables));
  return {};
}

Result<void> readTarget(const json& body, const FitLookup& lookup, FitJobSpec& spec) {
  auto it = body.find("target");
  if (it == body.end()) return invalid("target", "required: {\"brdf\": name, \"params\": {...}}");
  BRDFA_TRY(onlyKeys(*it, "target", {"brdf", "params"}));
  BRDFA_TRY_ASSIGN(std::shared_ptr<const BrdfEntry> entry, readBrdfName(*it, "target", lookup));
  spec.targetName = entry->name;
  spec.target = entry->definition;
  const json* params = it->contains("params") ? &(*it)["params"] : nullptr;
  BRDFA_TRY_ASSIGN(spec.targetParams,
                   paramsFromJson(*spec.target, spec.targetName, params, "target.params", &spec.notes));
  if (!spec.target->measuredTable.empty()) {
    std::optional<std::string> path = lookup.measuredPath(spec.target->measuredTable);
    if (!path)
      return makeError(ErrorCode::NotFound, "target.brdf: the table of '" + spec.targetName + "' is gone",
                       "target.brdf");
    spec.measuredPath = *path;
  }
  return {};
}

}  // namespace

Result<FitJobSpec> parseFitJob(const json& body, const FitLookup& lookup) {
  BRDFA_TRY(onlyKeys(body, "", {"model", "target", "loss", "restarts", "max_evaluations"}));
  FitJobSpec spec;
  BRDFA_TRY(readModel(body, lookup, spec));
  BRDFA_TRY(readTarget(body, lookup, spec));
  if (auto it = body.find("loss"); it != body.end())
    if (!it->is_string() || !fitLossFromName(it->get<std::string>(), spec.loss))
      return invalid("loss", std::string("must be ") + kFitLossChoices);
  BRDFA_TRY_ASSIGN(spec.restarts, readCount(body, "restarts", 1, kFitMaxRestarts, kFitDefaultRestarts));
  BRDFA_TRY_ASSIGN(spec.maxEvaluations,
                   readCount(body, "max_evaluations", kFitMinEvaluations, kFitMaxEvaluations, kFitDefaultEvaluations));
  return spec;
}

json fitJobRequestJson(const FitJobSpec& spec) {
  json fit = json::object(), start = json::object(), target = json::object();
  for (const FitParam& p : spec.fit) fit[p.name] = {floatForJson(p.lo), floatForJson(p.hi)};
  for (const BrdfParam& p : spec.model->definition->params)
    start[p.name] = paramValueToJson(p.type, spec.start.at(p.name));
  for (const BrdfParam& p : spec.target->params)
    target[p.name] = paramValueToJson(p.type, spec.targetParams.at(p.name));
  json out{{"model", {{"brdf", spec.modelName}, {"fit", fit}, {"params", start}}},
           {"target", {{"brdf", spec.targetName}, {"params", target}}},
           {"loss", fitLossName(spec.loss)},
           {"restarts", spec.restarts},
           {"max_evaluations", spec.maxEvaluations}};
  if (!spec.notes.empty()) out["notes"] = spec.notes;
  return out;
}

}  // namespace brdfa::server
