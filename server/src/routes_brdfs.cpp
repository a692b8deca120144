// The BRDF library over REST: list, read, compile-and-save, delete, validate.
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

}  // namespace

void registerBrdfRoutes(httplib::Server& server, Service& service) {
  server.Get("/api/brdfs", [&service](const httplib::Request&, httplib::Response& res) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& entry : service.library.list()) list.push_back(brdfEntryToJson(*entry, false));
    sendJson(res, list);
  });

  // Registered before /api/brdfs/{name} so "validate" is never taken as a name.
  server.Post("/api/brdfs/validate", [&service](const httplib::Request& req, httplib::Response& res) {
    auto text = readBrdfTextBody(req, res);
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
    if (!entry) return sendError(res, 404, "not_found", "no BRDF named '" + name + "'", "name");
    sendJson(res, brdfEntryToJson(*entry, true));
  });

  server.Put("/api/brdfs/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string name = req.matches[1];
    if (!isValidBrdfName(name))
      return sendError(res, 400, "invalid_argument",
                       "BRDF names are 1-64 characters of [A-Za-z0-9_-] and not 'inline' or 'validate'", "name");
    // Checked before compiling to fail fast; putUser checks again atomically.
    if (auto existing = service.library.find(name); existing && existing->builtin)
      return sendError(res, 409, "conflict", "BRDF '" + name + "' is built in and read-only", "name");
    auto text = readBrdfTextBody(req, res);
    if (!text) return;
    Result<Compiled> compiled = parseAndCompile(service, *text);
    if (!compiled) return sendError(res, compiled.error());
    auto outcome = service.library.putUser(name, *text, compiled->definition);
    if (outcome == BrdfLibrary::PutOutcome::BuiltinConflict)
      return sendError(res, 409, "conflict", "BRDF '" + name + "' is built in and read-only", "name");
    auto entry = service.library.find(name);
    nlohmann::json body = brdfEntryToJson(*entry, false);
    body.update(compileReport(compiled.value()));
    sendJson(res, body, outcome == BrdfLibrary::PutOutcome::Created ? 201 : 200);
  });

  server.Delete("/api/brdfs/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string name = req.matches[1];
    switch (service.library.remove(name)) {
      case BrdfLibrary::RemoveOutcome::Removed:
        res.status = 204;
        return;
      case BrdfLibrary::RemoveOutcome::NotFound:
        return sendError(res, 404, "not_found", "no BRDF named '" + name + "'", "name");
      case BrdfLibrary::RemoveOutcome::Builtin:
        return sendError(res, 409, "conflict", "BRDF '" + name + "' is built in and cannot be deleted", "name");
    }
  });
}

}  // namespace brdfa::server
