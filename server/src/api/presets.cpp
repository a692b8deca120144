// Presets: one person's named parameter sets of one BRDF, kept per person
// (BrdfCatalog::presetDir): each lists and changes their own; the teacher reads and deletes a
// student's with ?owner=<user>.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "api/brdf_access.h"
#include "api/routes.h"
#include "http/http_errors.h"
#include "json/brdf_json.h"
#include "util/atomic_file.h"

namespace brdfa::server {

namespace {

const char* const kPresetNameRule = "preset names are 1-64 characters of [A-Za-z0-9_-]";

bool readTextFile(const std::filesystem::path& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream text;
  text << in.rdbuf();
  out = text.str();
  return !in.bad();
}

// Whose presets a request means: the requester's own ("" for a teacher: the course's folder),
// or with ?owner= (the teacher only) that student's. Answers and returns nullopt when the
// owner is not the requester's to see (404, as for no presets) or `write` asks to change them.
std::optional<std::string> presetPerson(const httplib::Request& req, httplib::Response& res, bool write) {
  const Identity& who = requester(req);
  const std::string own = who.teacher() ? std::string() : who.user;
  if (!req.has_param("owner")) return own;
  const std::string owner = req.get_param_value("owner");
  if (owner == who.user) return own;
  if (!who.teacher() || !isValidUserName(owner)) {
    sendError(res, ErrorCode::NotFound, "no presets of '" + owner + "'", "owner");
    return std::nullopt;
  }
  if (write) {
    sendError(res, ErrorCode::Forbidden, "the teacher reads and deletes a student's presets; only they change them",
              "owner");
    return std::nullopt;
  }
  return owner;
}

// The preset route's BRDF (readable by the requester), the preset name and whose presets; false
// when it answered.
struct PresetTarget {
  std::string name, preset, person;
};
std::optional<PresetTarget> presetTarget(Service& service, const httplib::Request& req, httplib::Response& res,
                                         bool write, bool deleting = false) {
  PresetTarget t{req.matches[1], req.matches.size() > 2 ? std::string(req.matches[2]) : std::string(), {}};
  if (!readableBrdfOr404(service, requester(req), t.name, res)) return std::nullopt;
  if (req.matches.size() > 2 && !isValidBrdfName(t.preset)) {
    sendError(res, ErrorCode::InvalidArgument, kPresetNameRule, "preset");
    return std::nullopt;
  }
  std::optional<std::string> person = presetPerson(req, res, write && !deleting);
  if (!person) return std::nullopt;
  t.person = *person;
  return t;
}

}  // namespace

void registerPresetRoutes(httplib::Server& server, Service& service) {
  const std::string list = std::string("/api/brdfs/") + kBrdfPathName + "/presets";
  const std::string one = list + "/([^/]+)";

  server.Get(list, [&service](const httplib::Request& req, httplib::Response& res) {
    auto t = presetTarget(service, req, res, false);
    if (!t) return;
    std::vector<std::string> names;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(service.brdfs.presetDir(t->person, t->name), ec), end; !ec && it != end;
         it.increment(ec)) {
      const std::filesystem::path& path = it->path();
      std::string stem = path.stem().string();
      if (path.extension() == ".json" && isValidBrdfName(stem)) names.push_back(stem);
    }
    std::sort(names.begin(), names.end());
    sendJson(res, names);
  });

  server.Get(one, [&service](const httplib::Request& req, httplib::Response& res) {
    auto t = presetTarget(service, req, res, false);
    if (!t) return;
    std::string text;
    if (!readTextFile(std::filesystem::path(service.brdfs.presetDir(t->person, t->name)) / (t->preset + ".json"), text))
      return sendError(res, ErrorCode::NotFound, "BRDF '" + t->name + "' has no preset '" + t->preset + "'", "preset");
    nlohmann::json values = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (!values.is_object())
      return sendError(res, ErrorCode::StorageError,
                       "preset file of '" + t->name + "/" + t->preset + "' is not a JSON object");
    sendJson(res, values);
  });

  server.Put(one, [&service](const httplib::Request& req, httplib::Response& res) {
    auto t = presetTarget(service, req, res, true);
    if (!t) return;
    auto body = readJsonBody(req, res);
    if (!body) return;
    if (!body->is_object())
      return sendError(res, ErrorCode::InvalidArgument, "a preset is a JSON object of parameter values");
    // Checked and written against the BRDF the name holds now, with no BRDF store or removal in
    // between (BrdfLibrary::withEntry).
    service.brdfs.libraryFor(t->name)->withEntry(t->name, [&](std::shared_ptr<const BrdfEntry> entry) {
      if (!entry) return sendError(res, ErrorCode::NotFound, "no BRDF named '" + t->name + "'", "name");
      // Same rules as a scene object's "params"; stored normalized (bools as true/false).
      nlohmann::json values = nlohmann::json::object();
      for (auto it = body->begin(); it != body->end(); ++it) {
        std::string field = "params." + it.key();
        const BrdfParam* p = entry->definition->findParam(it.key());
        if (!p) {
          std::string known;
          for (const BrdfParam& q : entry->definition->params) known += (known.empty() ? "" : ", ") + q.name;
          return sendError(
              res, ErrorCode::InvalidArgument,
              field + ": BRDF '" + t->name + "' has no parameter '" + it.key() + "' (known: " + known + ")", field);
        }
        Result<Vec3> value = paramValueFromJson(*p, it.value(), field);
        if (!value) return sendError(res, value.error());
        values[p->name] = paramValueToJson(p->type, value.value());
      }
      std::filesystem::path target =
          std::filesystem::path(service.brdfs.presetDir(t->person, t->name)) / (t->preset + ".json");
      std::error_code ec;
      bool existed = std::filesystem::exists(target, ec);
      Result<void> written = writeFileAtomically(target, values.dump(2) + "\n");
      if (!written)
        return sendError(res, ErrorCode::StorageError,
                         "cannot save preset '" + t->preset + "': " + written.error().message);
      sendJson(res, values, existed ? 200 : 201);
    });
  });

  server.Delete(one, [&service](const httplib::Request& req, httplib::Response& res) {
    auto t = presetTarget(service, req, res, true, /*deleting=*/true);
    if (!t) return;
    service.brdfs.libraryFor(t->name)->withEntry(t->name, [&](std::shared_ptr<const BrdfEntry> entry) {
      if (!entry) return sendError(res, ErrorCode::NotFound, "no BRDF named '" + t->name + "'", "name");
      Result<void> removed =
          removeFileDurably(std::filesystem::path(service.brdfs.presetDir(t->person, t->name)) / (t->preset + ".json"));
      if (removed) {
        res.status = 204;
        return;
      }
      if (removed.error().code == ErrorCode::NotFound)
        return sendError(res, ErrorCode::NotFound, "BRDF '" + t->name + "' has no preset '" + t->preset + "'",
                         "preset");
      sendError(res, ErrorCode::StorageError, removed.error().message);
    });
  });
}

}  // namespace brdfa::server
