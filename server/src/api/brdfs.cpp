// The BRDF library over REST: list, read, compile-and-save, share, delete, validate (presets:
// api/presets.cpp).
#include <algorithm>

#include "api/brdf_access.h"
#include "api/routes.h"
#include "http/http_errors.h"
#include "http/request_body.h"
#include "json/brdf_json.h"

namespace brdfa::server {

namespace {

// Parse + compile. Either step's CompileError carries line-numbered diagnostics.
struct Compiled {
  std::shared_ptr<const BrdfDefinition> definition;
  CompileInfo info;
};

Result<Compiled> parseAndCompile(Service& service, const std::string& text) {
  BRDFA_TRY_ASSIGN(BrdfDefinition parsed, parseBrdf(text));
  auto def = std::make_shared<const BrdfDefinition>(std::move(parsed));
  BRDFA_TRY_ASSIGN(CompileInfo info, service.renderer->compileBrdf(*def));
  return Compiled{std::move(def), std::move(info)};
}

nlohmann::json compileReport(const Compiled& c) {
  std::vector<Diagnostic> warnings = c.definition->warnings;
  warnings.insert(warnings.end(), c.info.warnings.begin(), c.info.warnings.end());
  return {{"warnings", diagnosticsToJson(warnings)}, {"compile_ms", c.info.compileMs}, {"cached", c.info.cached}};
}

// A saved file that did not parse: listed so it can be seen, fixed (PUT) or deleted.
nlohmann::json brokenToJson(const BrokenBrdf& b, bool withSource) {
  nlohmann::json error{{"error", errorCodeName(b.error.code)}, {"message", b.error.message}};
  if (!b.error.diagnostics.empty()) error["diagnostics"] = diagnosticsToJson(b.error.diagnostics);
  nlohmann::json out{{"name", b.name}, {"format", nullptr}, {"builtin", false}, {"params", nlohmann::json::array()},
                     {"broken", true}, {"error", error}};
  if (withSource) out["source"] = b.source;
  return out;
}

}  // namespace

namespace {

void listBrdfs(Service& service, const httplib::Request& req, httplib::Response& res) {
  const Identity& who = requester(req);
  nlohmann::json list = nlohmann::json::array();
  for (const auto& entry : service.brdfs.list())
    if (canReadBrdf(who, *entry)) list.push_back(brdfEntryToJson(*entry, false));
  for (const BrokenBrdf& b : service.brdfs.listBroken())
    if (canReadBrdf(who, b)) list.push_back(brokenToJson(b, false));
  std::stable_sort(list.begin(), list.end(), [](const nlohmann::json& a, const nlohmann::json& b) {
    return a["name"].get<std::string>() < b["name"].get<std::string>();
  });
  sendJson(res, list);
}

// Registered before /api/brdfs/{name} so "validate" is never taken as a name.
void validateBrdf(Service& service, const httplib::Request& req, httplib::Response& res,
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
}

void getBrdf(Service& service, const httplib::Request& req, httplib::Response& res) {
  const Identity& who = requester(req);
  std::string name = req.matches[1];
  if (!isValidQualifiedBrdfName(name))
    return sendError(res, ErrorCode::InvalidArgument, std::string("BRDF ") + kBrdfNameRule, "name");
  if (auto entry = service.readableBrdf(who, name)) return sendJson(res, brdfEntryToJson(*entry, true));
  if (auto broken = service.brdfs.findBroken(name); broken && canReadBrdf(who, *broken))
    return sendJson(res, brokenToJson(*broken, true));
  sendError(res, ErrorCode::NotFound, "no BRDF named '" + name + "'", "name");
}

void putBrdf(Service& service, const httplib::Request& req, httplib::Response& res,
             const httplib::ContentReader& reader) {
  const Identity& who = requester(req);
  std::string name = req.matches[1];
  if (!mayWriteBrdfName(service, who, name, res)) return;
  // Checked before compiling to fail fast; putUser checks again atomically.
  if (auto existing = service.brdfs.find(name); existing && existing->builtin)
    return sendError(res, ErrorCode::Conflict, "BRDF '" + name + "' is built in and read-only", "name");
  auto text = readBrdfTextBody(req, res, reader);
  if (!text) return;
  Result<Compiled> compiled = parseAndCompile(service, *text);
  if (!compiled) return sendError(res, compiled.error());
  BrdfLibrary* library = service.brdfs.libraryFor(name, /*create=*/true);
  if (!library) return sendError(res, ErrorCode::StorageError, "cannot open the library of '" + name + "'");
  Error storeError;
  std::shared_ptr<const BrdfEntry> entry;  // what this PUT stored, even if a DELETE follows at once
  const int quota = service.quotaFor(who, &Quotas::brdfs);
  auto outcome = library->putUser(name, *text, compiled->definition, &storeError, &entry, size_t(quota));
  if (outcome == BrdfLibrary::PutOutcome::QuotaExceeded)
    return sendQuotaExceeded(res, "brdfs", uint64_t(quota), library->userEntryCount(),
                             "you have " + std::to_string(library->userEntryCount()) +
                                 " saved BRDFs, the most one person may (--quota-brdfs " + std::to_string(quota) +
                                 "); delete one (DELETE /api/brdfs/" + who.brdfNamespace() + "<name>)");
  if (outcome == BrdfLibrary::PutOutcome::StoreFailed)
    return sendError(res, ErrorCode::StorageError, "cannot save BRDF '" + name + "': " + storeError.message);
  if (outcome == BrdfLibrary::PutOutcome::BuiltinConflict)
    return sendError(res, ErrorCode::Conflict, "BRDF '" + name + "' is built in and read-only", "name");
  nlohmann::json body = brdfEntryToJson(*entry, false);
  body.update(compileReport(compiled.value()));
  sendJson(res, body, outcome == BrdfLibrary::PutOutcome::Created ? 201 : 200);
}

// {"shared": true|false}: whether classmates may read a student's BRDF.
void patchBrdf(Service& service, const httplib::Request& req, httplib::Response& res) {
  const Identity& who = requester(req);
  std::string name = req.matches[1];
  if (!mayWriteBrdfName(service, who, name, res)) return;
  auto body = readJsonBody(req, res);
  if (!body) return;
  auto shared = body->is_object() ? body->find("shared") : body->end();
  if (!body->is_object() || body->size() != 1 || shared == body->end() || !shared->is_boolean())
    return sendError(res, ErrorCode::InvalidArgument, "send {\"shared\": true} or {\"shared\": false}", "shared");
  if (brdfNameOwner(name).empty())
    return sendError(res, ErrorCode::InvalidArgument, "course BRDFs are read by everyone already", "name");
  Result<bool> changed = service.brdfs.libraryFor(name)->setShared(name, shared->get<bool>());
  if (!changed) return sendError(res, ErrorCode::StorageError, changed.error().message);
  if (!changed.value()) return sendError(res, ErrorCode::NotFound, "no BRDF named '" + name + "'", "name");
  if (auto entry = service.brdfs.find(name)) return sendJson(res, brdfEntryToJson(*entry, false));
  sendJson(res, {{"name", name}, {"shared", shared->get<bool>()}});  // a broken one
}

void deleteBrdf(Service& service, const httplib::Request& req, httplib::Response& res) {
  const Identity& who = requester(req);
  std::string name = req.matches[1];
  if (!isValidQualifiedBrdfName(name))
    return sendError(res, ErrorCode::InvalidArgument, std::string("BRDF ") + kBrdfNameRule, "name");
  auto entry = service.brdfs.find(name);
  auto broken = entry ? std::nullopt : service.brdfs.findBroken(name);
  const bool visible = (entry && canReadBrdf(who, *entry)) || (broken && canReadBrdf(who, *broken));
  if (!visible) return sendError(res, ErrorCode::NotFound, "no BRDF named '" + name + "'", "name");
  if (entry && entry->builtin)
    return sendError(res, ErrorCode::Conflict, "BRDF '" + name + "' is built in and cannot be deleted", "name");
  if (!canDelete(who, std::string(brdfNameOwner(name))))
    return sendError(res, ErrorCode::Forbidden, "only its owner or the teacher deletes BRDF '" + name + "'", "name");
  Error storeError;
  switch (service.brdfs.libraryFor(name)->remove(name, &storeError)) {
    case BrdfLibrary::RemoveOutcome::Removed:  // every person's presets of it too (BrdfCatalog)
      res.status = 204;
      return;
    case BrdfLibrary::RemoveOutcome::StoreFailed:
      return sendError(res, ErrorCode::StorageError, "cannot delete BRDF '" + name + "': " + storeError.message);
    case BrdfLibrary::RemoveOutcome::NotFound:
      return sendError(res, ErrorCode::NotFound, "no BRDF named '" + name + "'", "name");
    case BrdfLibrary::RemoveOutcome::Builtin:
      return sendError(res, ErrorCode::Conflict, "BRDF '" + name + "' is built in and cannot be deleted", "name");
  }
}

}  // namespace

void registerBrdfRoutes(httplib::Server& server, Service& service) {
  // Before /api/brdfs/{name}: "<name>/presets" must never be taken as a qualified name.
  registerPresetRoutes(server, service);
  server.Get("/api/brdfs", withService(service, listBrdfs));
  server.Post("/api/brdfs/validate", withService(service, validateBrdf));

  const std::string byName = std::string("/api/brdfs/") + kBrdfPathName;
  server.Get(byName, withService(service, getBrdf));
  server.Put(byName, withService(service, putBrdf));
  server.Patch(byName, withService(service, patchBrdf));
  server.Delete(byName, withService(service, deleteBrdf));
}

}  // namespace brdfa::server
