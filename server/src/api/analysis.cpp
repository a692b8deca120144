// POST /api/analysis/{polar|lobe|albedo|slice}: the Analysis tab's plots of one or more BRDFs
// (docs/api.md "Analysis"). The data comes from the renderer (brdf_plots.h); this file parses the
// request and writes JSON or CSV.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "api/routes.h"
#include "brdfa/brdf_plots.h"
#include "http/http_errors.h"
#include "http/request_body.h"
#include "json/brdf_json.h"
#include "json/json_numbers.h"
#include "json/scene_json.h"

namespace brdfa::server {

namespace {

using nlohmann::json;

constexpr size_t kMaxSeries = 8;

struct Series {
  std::string label;
  std::string brdfName;  // "inline" for a series that carries its source
  std::shared_ptr<const BrdfDefinition> brdf;
  ParamSetting params;
  std::vector<std::string> notes;
};

Error bad(const std::string& field, const std::string& message) {
  return makeError(ErrorCode::InvalidArgument, field + ": " + message, field);
}

Result<double> readNumber(const json& body, const char* key, double fallback) {
  auto it = body.find(key);
  if (it == body.end()) return fallback;
  if (!it->is_number() || !std::isfinite(it->get<double>())) return bad(key, "must be a number");
  return it->get<double>();
}

Result<std::vector<Series>> readSeries(const json& body, Service& service, const Identity& who) {
  auto it = body.find("series");
  if (it == body.end() || !it->is_array() || it->empty() || it->size() > kMaxSeries)
    return bad("series", "must be an array of 1.." + std::to_string(kMaxSeries) +
                             " objects {\"brdf\": name or \"source\": text, \"params\": {...}, \"label\": text}");
  std::vector<Series> out;
  for (size_t i = 0; i < it->size(); ++i) {
    const json& s = (*it)[i];
    const std::string at = "series[" + std::to_string(i) + "]";
    if (!s.is_object()) return bad(at, "must be an object");
    for (auto kv = s.begin(); kv != s.end(); ++kv)
      if (kv.key() != "brdf" && kv.key() != "source" && kv.key() != "params" && kv.key() != "label")
        return bad(at + "." + kv.key(), "unknown key (known: brdf, source, params, label)");
    Series series;
    if (auto src = s.find("source"); src != s.end()) {
      if (!src->is_string()) return bad(at + ".source", "must be a string of .brdf text");
      if (src->get_ref<const std::string&>().size() > kMaxBrdfSource)
        return makeError(ErrorCode::InvalidArgument,
                         at + ".source: larger than " + std::to_string(kMaxBrdfSource) + " bytes", at + ".source");
      Result<BrdfDefinition> def = parseBrdf(src->get<std::string>());
      if (!def) return def.takeError();
      series.brdf = std::make_shared<const BrdfDefinition>(std::move(def.value()));
      series.brdfName = kInlineBrdfName;
    } else {
      auto name = s.find("brdf");
      if (name == s.end() || !name->is_string()) return bad(at + ".brdf", "must name a BRDF (or give \"source\")");
      series.brdfName = name->get<std::string>();
      auto entry = service.readableBrdf(who, series.brdfName);
      // Someone else's BRDF is as unknown as one that does not exist.
      if (!entry)
        return makeError(ErrorCode::NotFound, at + ".brdf: unknown BRDF '" + series.brdfName + "'", at + ".brdf");
      series.brdf = entry->definition;
    }
    const json* params = nullptr;
    if (auto p = s.find("params"); p != s.end()) params = &*p;
    BRDFA_TRY_ASSIGN(ParamSetting values,
                     paramsFromJson(*series.brdf, series.brdfName, params, at + ".params", &series.notes));
    series.params = std::move(values);
    series.label = series.brdfName;
    if (auto l = s.find("label"); l != s.end()) {
      if (!l->is_string() || l->get_ref<const std::string&>().size() > 200)
        return bad(at + ".label", "must be a string of at most 200 bytes");
      series.label = l->get<std::string>();
    }
    out.push_back(std::move(series));
  }
  return out;
}

Result<PlotRequest> readRequest(PlotKind kind, const json& body) {
  static const char* kKeys[] = {"series", "theta_i", "quantity", "resolution", "phi_d", "theta_v", "samples", "format"};
  for (auto kv = body.begin(); kv != body.end(); ++kv) {
    bool known = false;
    for (const char* k : kKeys) known = known || kv.key() == k;
    if (!known)
      return bad(kv.key(),
                 "unknown key (known: series, theta_i, quantity, resolution, phi_d, theta_v, samples, format)");
  }
  PlotRequest r;
  r.kind = kind;
  BRDFA_TRY_ASSIGN(double thetaI, readNumber(body, "theta_i", r.thetaIDeg));
  r.thetaIDeg = thetaI;
  BRDFA_TRY_ASSIGN(double phiD, readNumber(body, "phi_d", r.phiDDeg));
  r.phiDDeg = phiD;
  Result<double> resolution = readNumber(body, "resolution", 0);
  if (!resolution) return resolution.takeError();
  if (resolution.value() != std::floor(resolution.value()) || std::fabs(resolution.value()) > 1e6)
    return bad("resolution", "must be an integer");
  r.resolution = int(resolution.value());
  Result<double> samples = readNumber(body, "samples", r.samples);
  if (!samples) return samples.takeError();
  if (samples.value() != std::floor(samples.value()) || samples.value() < 0 || samples.value() > 1e9)
    return bad("samples", "must be an integer");
  r.samples = uint32_t(samples.value());
  if (auto q = body.find("quantity"); q != body.end()) {
    if (*q == "f")
      r.cosine = false;
    else if (*q == "f_cos")
      r.cosine = true;
    else
      return bad("quantity", "must be \"f\" or \"f_cos\"");
  }
  if (auto v = body.find("theta_v"); v != body.end()) {
    if (!v->is_array()) return bad("theta_v", "must be an array of angles in degrees");
    for (const json& a : *v) {
      if (!a.is_number()) return bad("theta_v", "must be an array of angles in degrees");
      r.viewDeg.push_back(a.get<double>());
    }
  }
  return r;
}

// [r, g, b], or null where the plot has no value (a slice below the horizon: all three NaN).
json rgb(const Vec3& v) {
  if (!std::isfinite(v[0]) && !std::isfinite(v[1]) && !std::isfinite(v[2])) return nullptr;
  json out = json::array();
  for (float c : v) out.push_back(std::isfinite(c) ? json(floatForJson(c)) : json(nullptr));  // NaN: no value
  return out;
}

// Values of one series, shaped by the plot's axes (see brdf_plots.h for the order).
json seriesValues(const Plot& plot, const std::vector<Vec3>& values) {
  if (plot.kind == PlotKind::Polar) {
    const size_t n = plot.axes[0].values.size();
    json byPlane = json::object();
    for (size_t p = 0; p < plot.planes.size(); ++p) {
      json row = json::array();
      for (size_t i = 0; i < n; ++i) row.push_back(rgb(values[p * n + i]));
      byPlane[plot.planes[p]] = std::move(row);
    }
    return byPlane;
  }
  if (plot.axes.size() == 1) {  // albedo
    json row = json::array();
    for (const Vec3& v : values) row.push_back(rgb(v));
    return row;
  }
  const size_t fast = plot.axes[0].values.size(), slow = plot.axes[1].values.size();
  json rows = json::array();
  for (size_t j = 0; j < slow; ++j) {
    json row = json::array();
    for (size_t i = 0; i < fast; ++i) row.push_back(rgb(values[j * fast + i]));
    rows.push_back(std::move(row));
  }
  return rows;
}

json toJson(const PlotRequest& request, const std::vector<Series>& series, const std::vector<Plot>& plots, double ms) {
  json out{{"kind", plotKindName(request.kind)}};
  if (request.kind == PlotKind::Polar || request.kind == PlotKind::Lobe) {
    out["theta_i"] = request.thetaIDeg;
    out["quantity"] = request.cosine ? "f_cos" : "f";
  }
  if (request.kind == PlotKind::Slice) out["phi_d"] = request.phiDDeg;
  json axes = json::object();
  for (const PlotAxis& a : plots.front().axes) axes[a.name] = a.values;
  out["axes"] = axes;
  if (!plots.front().planes.empty()) out["planes"] = plots.front().planes;
  json list = json::array();
  for (size_t i = 0; i < series.size(); ++i) {
    const Series& s = series[i];
    const Plot& plot = plots[i];
    json params = json::object();
    for (const BrdfParam& p : s.brdf->params) params[p.name] = paramValueToJson(p.type, s.params.at(p.name));
    json item{{"label", s.label},
              {"brdf", s.brdfName},
              {"params", params},
              {"notes", s.notes},
              {"values", seriesValues(plot, plot.values.front())},
              {"ms", plot.ms}};
    if (request.kind == PlotKind::Albedo) {
      item["std_error"] = seriesValues(plot, plot.stdError.front());
      item["estimator"] = plot.estimator;
      item["samples"] = plot.samples;
    }
    list.push_back(std::move(item));
  }
  out["series"] = std::move(list);
  out["ms"] = ms;
  return out;
}

// One row per value: series index, label, the axes' values, r, g, b (empty where there is no
// value), and for the albedo the standard errors.
std::string toCsv(const PlotRequest& request, const std::vector<Series>& series, const std::vector<Plot>& plots) {
  std::ostringstream csv;
  const Plot& first = plots.front();
  csv << "series,label";
  if (request.kind == PlotKind::Polar) csv << ",plane";
  for (const PlotAxis& a : first.axes) csv << "," << a.name;
  csv << ",r,g,b";
  if (request.kind == PlotKind::Albedo) csv << ",r_std_error,g_std_error,b_std_error";
  csv << "\n";
  auto number = [](float v) {
    if (!std::isfinite(v)) return std::string();
    char s[32];
    std::snprintf(s, sizeof s, "%.9g", v);
    return std::string(s);
  };
  auto quoted = [](const std::string& text) {  // RFC 4180: in quotes, quotes doubled
    std::string q = "\"";
    for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  for (size_t s = 0; s < series.size(); ++s) {
    const Plot& plot = plots[s];
    const std::vector<Vec3>& values = plot.values.front();
    const size_t fast = plot.axes[0].values.size();
    for (size_t i = 0; i < values.size(); ++i) {
      csv << s << "," << quoted(series[s].label);
      if (request.kind == PlotKind::Polar) csv << "," << plot.planes[i / fast];
      csv << "," << plot.axes[0].values[i % fast];
      if (plot.axes.size() > 1) csv << "," << plot.axes[1].values[i / fast];
      for (float c : values[i]) csv << "," << number(c);
      if (request.kind == PlotKind::Albedo)
        for (float c : plot.stdError.front()[i]) csv << "," << number(c);
      csv << "\n";
    }
  }
  return csv.str();
}

}  // namespace

void registerAnalysisRoutes(httplib::Server& server, Service& service) {
  server.Post(R"(/api/analysis/([a-z]+))", [&service](const httplib::Request& req, httplib::Response& res) {
    PlotKind kind;
    if (!plotKindFromName(req.matches[1], kind))
      return sendError(res, ErrorCode::NotFound,
                       "unknown analysis '" + std::string(req.matches[1]) + "' (known: polar, lobe, albedo, slice)");
    auto parsed = readJsonBody(req, res);
    if (!parsed) return;
    const json& body = *parsed;
    if (!body.is_object()) return sendError(res, ErrorCode::InvalidArgument, "the body must be a JSON object");
    bool csv = false;
    std::string format = req.has_param("format") ? req.get_param_value("format") : body.value("format", "json");
    if (format == "csv")
      csv = true;
    else if (format != "json")
      return sendError(res, ErrorCode::InvalidArgument, "format must be json or csv", "format");
    Result<PlotRequest> request = readRequest(kind, body);
    if (!request) return sendError(res, request.error());
    if (Result<void> valid = checkPlotRequest(request.value()); !valid) return sendError(res, valid.error());
    Result<std::vector<Series>> series = readSeries(body, service, requester(req));
    if (!series) return sendError(res, series.error());

    // The device is shared with every session: analyses queue with the one-shot renders.
    RenderQuotaGuard quota;
    RenderSlotGuard slot;
    if (!takeRenderSlot(service, req, res, slot, quota)) return;

    const auto t0 = std::chrono::steady_clock::now();
    std::vector<Plot> plots;
    for (const Series& s : series.value()) {
      if (service.stopping) return sendError(res, ErrorCode::Unavailable, "server is shutting down");
      Result<Plot> plot = plotBrdf(*service.renderer, *s.brdf, {s.params}, request.value());
      if (!plot) {
        Error e = plot.error();
        e.message = "series '" + s.label + "': " + e.message;
        return sendError(res, e);
      }
      plots.push_back(std::move(plot.value()));
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (csv)
      res.set_content(toCsv(request.value(), series.value(), plots), "text/csv; charset=utf-8");
    else
      res.set_content(toJson(request.value(), series.value(), plots, ms).dump(), "application/json");
  });
}

}  // namespace brdfa::server
