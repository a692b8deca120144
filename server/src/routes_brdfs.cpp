// The BRDF library over REST: list, read, compile-and-save, delete, validate, presets.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "brdfa_server/atomic_file.h"
#include "brdfa_server/brdf_json.h"
#include "brdfa_server/http_errors.h"
#include "brdfa_server/request_body.h"
#include "routes.h"

namespace brdfa::server {

namespace {

// Parse + compile. Either step's CompileError carries line-numbered diagnostics.
struct Compiled {
  std::shared_ptr<const BrdfDefinition> definition;
  CompileInfo info;
};

Result<Compiled> parseAndCompile(Service& service, const std::string& text) {
  Result<BrdfDefinition> parsed = parseBrdf(text);
  if (!parsed) return parsed.takeError();
  auto def = std::make_shared<const BrdfDefinition>(std::move(parsed.value()));
  Result<CompileInfo> info = service.renderer->compileBrdf(*def);
  if (!info) return info.takeError();
  return Compiled{std::move(def), std::move(info.value())};
}

nlohmann::json compileReport(const Compiled& c) {
  std::vector<Diagnostic> warnings = c.definition->warnings;
  warnings.insert(warnings.end(), c.info.warnings.begin(), c.info.warnings.end());
  return {{"warnings", diagnosticsToJson(warnings)}, {"compile_ms", c.info.compileMs}, {"cached", c.info.cached}};
}

// A saved file that did not parse: listed so it can be seen, fixed (PUT) or deleted.
nlohmann::json brokenToJson(const BrokenBrdf& b, bool withSource) {
  nlohmann::json error{{"error", errorName(b.error.code)}, {"message", b.error.message}};
  if (!b.error.diagnostics.empty()) error["diagnostics"] = diagnosticsToJson(b.error.diagnostics);
  nlohmann::json out{{"name", b.name}, {"format", nullptr}, {"builtin", false}, {"params", nlohmann::json::array()},
                     {"broken", true},   {"error", error}};
  if (withSource) out["source"] = b.source;
  return out;
}

const char* const kNameRule = "names are 1-64 characters of [A-Za-z0-9_-] and not 'inline' or 'validate'";

// The BRDF a preset route names; answers 400/404 and returns null when there is none.
std::shared_ptr<const BrdfEntry> presetBrdf(Service& service, const std::string& name, httplib::Response& res) {
  if (!isValidBrdfName(name)) {
    sendError(res, 400, "invalid_argument", std::string("BRDF ") + kNameRule, "name");
    return nullptr;
  }
  auto entry = service.library.find(name);
  if (!entry) sendError(res, 404, "not_found", "no BRDF named '" + name + "'", "name");
  return entry;
}

bool readTextFile(const std::filesystem::path& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream text;
  text << in.rdbuf();
  out = text.str();
  return !in.bad();
}

}  // namespace

void registerBrdfRoutes(httplib::Server& server, Service& service) {
  server.Get("/api/brdfs", [&service](const httplib::Request&, httplib::Response& res) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& entry : service.library.list()) list.push_back(brdfEntryToJson(*entry, false));
    for (const BrokenBrdf& b : service.library.listBroken()) list.push_back(brokenToJson(b, false));
    std::stable_sort(list.begin(), list.end(), [](const nlohmann::json& a, const nlohmann::json& b) {
      return a["name"].get<std::string>() < b["name"].get<std::string>();
    });
    sendJson(res, list);
  });

  // Registered before /api/brdfs/{name} so "validate" is never taken as a name.
  server.Post("/api/brdfs/validate", [&service](const httplib::Request& req, httplib::Response& res,
                                                const httplib::ContentReader& reader) {
    auto text = readBrdfTextBody(req, res, reader);
    if (!text) return;
    Result<Compiled> compiled = parseAndCompile(service, *text);
    if (!compiled) return sendError(res, compiled.error());
    nlohmann::json body = compileReport(compiled.value());
    body["ok"] = true;
    body["format"] = brdfFormatName(compiled->definition->format);
    body["params"] = paramsToJson(compiled->definition->params);
    sendJson(res, body);
  });

  server.Get("/api/brdfs/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string name = req.matches[1];
    auto entry = service.library.find(name);
    if (entry) return sendJson(res, brdfEntryToJson(*entry, true));
    if (auto broken = service.library.findBroken(name)) return sendJson(res, brokenToJson(*broken, true));
    sendError(res, 404, "not_found", "no BRDF named '" + name + "'", "name");
  });

  server.Put("/api/brdfs/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res,
                                               const httplib::ContentReader& reader) {
    std::string name = req.matches[1];
    if (!isValidBrdfName(name))
      return sendError(res, 400, "invalid_argument",
                       "BRDF names are 1-64 characters of [A-Za-z0-9_-] and not 'inline' or 'validate'", "name");
    // Checked before compiling to fail fast; putUser checks again atomically.
    if (auto existing = service.library.find(name); existing && existing->builtin)
      return sendError(res, 409, "conflict", "BRDF '" + name + "' is built in and read-only", "name");
    auto text = readBrdfTextBody(req, res, reader);
    if (!text) return;
    Result<Compiled> compiled = parseAndCompile(service, *text);
    if (!compiled) return sendError(res, compiled.error());
    Error storeError;
    std::shared_ptr<const BrdfEntry> entry;  // what this PUT stored, even if a DELETE follows at once
    auto outcome = service.library.putUser(name, *text, compiled->definition, &storeError, &entry);
    if (outcome == BrdfLibrary::PutOutcome::StoreFailed)
      return sendError(res, 500, "storage_error", "cannot save BRDF '" + name + "': " + storeError.message);
    if (outcome == BrdfLibrary::PutOutcome::BuiltinConflict)
      return sendError(res, 409, "conflict", "BRDF '" + name + "' is built in and read-only", "name");
    nlohmann::json body = brdfEntryToJson(*entry, false);
    body.update(compileReport(compiled.value()));
    sendJson(res, body, outcome == BrdfLibrary::PutOutcome::Created ? 201 : 200);
  });

  server.Delete("/api/brdfs/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string name = req.matches[1];
    if (!isValidBrdfName(name)) return sendError(res, 400, "invalid_argument", std::string("BRDF ") + kNameRule, "name");
    Error storeError;
    switch (service.library.remove(name, &storeError)) {
      case BrdfLibrary::RemoveOutcome::Removed:  // its presets with it (BrdfLibrary::remove)
        res.status = 204;
        return;
      case BrdfLibrary::RemoveOutcome::StoreFailed:
        return sendError(res, 500, "storage_error", "cannot delete BRDF '" + name + "': " + storeError.message);
      case BrdfLibrary::RemoveOutcome::NotFound:
        return sendError(res, 404, "not_found", "no BRDF named '" + name + "'", "name");
      case BrdfLibrary::RemoveOutcome::Builtin:
        return sendError(res, 409, "conflict", "BRDF '" + name + "' is built in and cannot be deleted", "name");
    }
  });

  // Presets: named parameter sets of one BRDF, <data dir>/presets/<brdf>/<preset>.json.
  server.Get("/api/brdfs/([^/]+)/presets", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string name = req.matches[1];
    if (!presetBrdf(service, name, res)) return;
    std::vector<std::string> names;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(service.library.presetDir(name), ec), end; !ec && it != end; it.increment(ec)) {
      const std::filesystem::path& path = it->path();
      std::string stem = path.stem().string();
      if (path.extension() == ".json" && isValidBrdfName(stem)) names.push_back(stem);
    }
    std::sort(names.begin(), names.end());
    sendJson(res, names);
  });

  server.Get("/api/brdfs/([^/]+)/presets/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string name = req.matches[1], preset = req.matches[2];
    if (!presetBrdf(service, name, res)) return;
    if (!isValidBrdfName(preset))
      return sendError(res, 400, "invalid_argument", std::string("preset ") + kNameRule, "preset");
    std::string text;
    if (!readTextFile(std::filesystem::path(service.library.presetDir(name)) / (preset + ".json"), text))
      return sendError(res, 404, "not_found", "BRDF '" + name + "' has no preset '" + preset + "'", "preset");
    nlohmann::json values = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (!values.is_object())
      return sendError(res, 500, "storage_error", "preset file of '" + name + "/" + preset + "' is not a JSON object");
    sendJson(res, values);
  });

  server.Put("/api/brdfs/([^/]+)/presets/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string name = req.matches[1], preset = req.matches[2];
    if (!presetBrdf(service, name, res)) return;
    if (!isValidBrdfName(preset))
      return sendError(res, 400, "invalid_argument", std::string("preset ") + kNameRule, "preset");
    auto body = readJsonBody(req, res);
    if (!body) return;
    if (!body->is_object())
      return sendError(res, 400, "invalid_argument", "a preset is a JSON object of parameter values");
    // Checked and written against the BRDF the name holds now, with no BRDF store or removal in
    // between (BrdfLibrary::withEntry).
    service.library.withEntry(name, [&](std::shared_ptr<const BrdfEntry> entry) {
      if (!entry) return sendError(res, 404, "not_found", "no BRDF named '" + name + "'", "name");
      // Same rules as a scene object's "params"; stored normalized (bools as true/false).
      nlohmann::json values = nlohmann::json::object();
      for (auto it = body->begin(); it != body->end(); ++it) {
        std::string field = "params." + it.key();
        const BrdfParam* p = entry->definition->findParam(it.key());
        if (!p) {
          std::string known;
          for (const BrdfParam& q : entry->definition->params) known += (known.empty() ? "" : ", ") + q.name;
          return sendError(res, 400, "invalid_argument",
                           field + ": BRDF '" + name + "' has no parameter '" + it.key() + "' (known: " + known + ")",
                           field);
        }
        Result<Vec3> value = paramValueFromJson(*p, it.value(), field);
        if (!value) return sendError(res, value.error());
        values[p->name] = paramValueToJson(p->type, value.value());
      }
      std::filesystem::path target = std::filesystem::path(service.library.presetDir(name)) / (preset + ".json");
      std::error_code ec;
      bool existed = std::filesystem::exists(target, ec);
      Result<void> written = writeFileAtomically(target, values.dump(2) + "\n");
      if (!written)
        return sendError(res, 500, "storage_error", "cannot save preset '" + preset + "': " + written.error().message);
      sendJson(res, values, existed ? 200 : 201);
    });
  });

  server.Delete("/api/brdfs/([^/]+)/presets/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string name = req.matches[1], preset = req.matches[2];
    if (!presetBrdf(service, name, res)) return;
    if (!isValidBrdfName(preset))
      return sendError(res, 400, "invalid_argument", std::string("preset ") + kNameRule, "preset");
    service.library.withEntry(name, [&](std::shared_ptr<const BrdfEntry> entry) {
      if (!entry) return sendError(res, 404, "not_found", "no BRDF named '" + name + "'", "name");
      Result<void> removed =
          removeFileDurably(std::filesystem::path(service.library.presetDir(name)) / (preset + ".json"));
      if (removed) {
        res.status = 204;
        return;
      }
      if (removed.error().code == ErrorCode::NotFound)
        return sendError(res, 404, "not_found", "BRDF '" + name + "' has no preset '" + preset + "'", "preset");
      sendError(res, 500, "storage_error", removed.error().message);
    });
  });
}

}  // namespace brdfa::server
