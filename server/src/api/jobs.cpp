// Jobs over REST: POST /api/jobs/validate (batch tests), /api/jobs/convergence (sampling
// strategies at equal time) and /api/jobs/fit (a model's parameters fitted to a target) queue,
// GET /api/jobs/{id} reports, DELETE /api/jobs/{id} cancels.
#include <algorithm>
#include <set>

#include "api/routes.h"
#include "http/http_errors.h"
#include "jobs/convergence_job.h"
#include "jobs/fit_job.h"

namespace brdfa::server {

namespace {

// The requester's JobOwner, with their --quota-jobs.
JobOwner jobOwner(const Service& service, const Identity& who) {
  return JobOwner{who.owner(), size_t(service.quotaFor(who, &Quotas::jobs))};
}

// Answers a refused submit: the person's quota (429 quota_exceeded), else the server's cap.
void sendJobRefusal(httplib::Response& res, const JobSubmitted& submitted, const JobOwner& owner,
                    const std::string& serverCap) {
  if (submitted.quotaFull)
    return sendQuotaExceeded(res, "jobs", owner.maxOpen, submitted.ownerOpen,
                             "you have " + std::to_string(submitted.ownerOpen) +
                                 " jobs queued or running, the most one person may (--quota-jobs " +
                                 std::to_string(owner.maxOpen) +
                                 "); wait for one or cancel it (DELETE /api/jobs/{id})");
  sendError(res, ErrorCode::TooManyJobs, serverCap);
}

// Whether the requester may see job `id` (its owner, the teacher); else answers 404, exactly as
// for an unknown id.
bool jobVisible(Service& service, const httplib::Request& req, httplib::Response& res, const std::string& id) {
  std::optional<std::string> owner = service.jobs->ownerOf(id);
  if (owner && canRead(requester(req), *owner)) return true;
  sendError(res, ErrorCode::NotFound, "no job '" + id + "'", "id");
  return false;
}

// Queues a one-piece job: its request with "id" and "kind" added, or null once a refusal was
// answered.
nlohmann::json submitOnePiece(Service& service, httplib::Response& res, const Identity& who, JobKind kind,
                              nlohmann::json request, JobRunner run) {
  const JobOwner owner = jobOwner(service, who);
  JobSubmitted submitted = service.jobs->submitRunner(kind, request, std::move(run), owner);
  if (!submitted.id) {
    sendJobRefusal(res, submitted, owner,
                   "at most " + std::to_string(kMaxOpenRunnerJobs) +
                       " convergence and fit jobs wait or run at once (and " + std::to_string(kMaxJobs) +
                       " jobs are kept); try later or cancel one");
    return nullptr;
  }
  request["id"] = *submitted.id;
  request["kind"] = jobKindName(kind);
  return request;
}

// POST /api/jobs/fit: parses the request as its requester may name BRDFs and queues the fit.
void postFitJob(Service& service, const httplib::Request& req, httplib::Response& res) {
  if (refuseWhileDraining(service, res)) return;
  auto body = readJsonBody(req, res);
  if (!body) return;
  const Identity& who = requester(req);
  FitLookup lookup{[&](const std::string& name) { return service.readableBrdf(who, name); },
                   [&](const std::string& id) { return service.assets->storedFile(id); }};
  Result<FitJobSpec> spec = parseFitJob(*body, lookup);
  if (!spec) return sendError(res, spec.error());
  nlohmann::json request = fitJobRequestJson(spec.value());
  std::shared_ptr<Renderer> renderer = service.renderer;
  auto run = [renderer, spec = std::move(spec.value())](JobContext& context) {
    return runFitJob(*renderer, spec, context);
  };
  request = submitOnePiece(service, res, who, JobKind::Fit, std::move(request), std::move(run));
  if (!request.is_null()) sendJson(res, request, 202);
}

}  // namespace

void registerJobRoutes(httplib::Server& server, Service& service) {
  server.Post("/api/jobs/validate", [&service](const httplib::Request& req, httplib::Response& res) {
    if (refuseWhileDraining(service, res)) return;
    auto body = readJsonBody(req, res);
    if (!body) return;
    if (!body->is_object())
      return sendError(res, ErrorCode::InvalidArgument, "the body is {\"names\": [...]} or {\"all\": true}");
    for (auto it = body->begin(); it != body->end(); ++it)
      if (it.key() != "names" && it.key() != "all")
        return sendError(res, ErrorCode::InvalidArgument, "unknown key '" + it.key() + "' (known: names, all)",
                         it.key());
    bool all = false;
    if (auto it = body->find("all"); it != body->end()) {
      if (!it->is_boolean()) return sendError(res, ErrorCode::InvalidArgument, "all: must be true or false", "all");
      all = it->get<bool>();
    }
    auto namesIt = body->find("names");
    if (all == (namesIt != body->end()))
      return sendError(res, ErrorCode::InvalidArgument, "give exactly one of \"names\": [...] or \"all\": true");

    const Identity& who = requester(req);
    std::vector<JobItem> items;
    if (all) {
      // "all": the built-ins, the course and the requester's own (not what classmates share).
      auto mine = [&](const std::string& owner) { return owner.empty() || owner == who.libraryOwner(); };
      for (const auto& entry : service.brdfs.list())
        if (!isScratchBrdf(entry->name) && mine(entry->owner))
          items.push_back(JobItem{entry->name, entry->definition, {}});
      for (BrokenBrdf& b : service.brdfs.listBroken())
        if (!isScratchBrdf(b.name) && mine(b.owner)) items.push_back(JobItem{b.name, nullptr, std::move(b.error)});
      std::sort(items.begin(), items.end(), [](const JobItem& a, const JobItem& b) { return a.name < b.name; });
    } else {
      if (!namesIt->is_array())
        return sendError(res, ErrorCode::InvalidArgument, "names: must be an array of BRDF names", "names");
      if (namesIt->empty()) return sendError(res, ErrorCode::InvalidArgument, "names: the list is empty", "names");
      std::set<std::string> seen;
      nlohmann::json unknown = nlohmann::json::array();
      for (size_t i = 0; i < namesIt->size(); ++i) {
        const nlohmann::json& n = (*namesIt)[i];
        std::string field = "names[" + std::to_string(i) + "]";
        if (!n.is_string()) return sendError(res, ErrorCode::InvalidArgument, field + ": must be a string", field);
        std::string name = n.get<std::string>();
        if (!seen.insert(name).second) continue;  // duplicates are tested once
        if (auto entry = service.readableBrdf(who, name))
          items.push_back(JobItem{name, entry->definition, {}});
        else if (auto broken = service.brdfs.findBroken(name); broken && canReadBrdf(who, *broken))
          items.push_back(JobItem{name, nullptr, std::move(broken->error)});
        else
          unknown.push_back(name);
      }
      if (!unknown.empty()) {
        std::string list;
        for (const auto& u : unknown) list += (list.empty() ? "" : ", ") + u.get<std::string>();
        return sendJson(res,
                        {{"error", errorCodeName(ErrorCode::NotFound)},
                         {"message", "no BRDF named " + list},
                         {"field", "names"},
                         {"names", unknown}},
                        errorHttpStatus(ErrorCode::NotFound));
      }
    }
    if (items.empty()) return sendError(res, ErrorCode::InvalidArgument, "no BRDFs to test");
    size_t total = items.size();
    const JobOwner owner = jobOwner(service, who);
    JobSubmitted submitted = service.jobs->submit(std::move(items), owner);
    if (!submitted.id)
      return sendJobRefusal(res, submitted, owner,
                            "at most " + std::to_string(kMaxJobs) + " jobs are kept and none has finished; try later");
    sendJson(res, {{"id", *submitted.id}, {"total", total}}, 202);
  });

  server.Post("/api/jobs/convergence", [&service](const httplib::Request& req, httplib::Response& res) {
    if (refuseWhileDraining(service, res)) return;
    auto body = readJsonBody(req, res);
    if (!body) return;
    const Identity& who = requester(req);
    Result<ConvergenceJobSpec> spec = parseConvergenceJob(*body, service.resolver(who));
    if (!spec) return sendError(res, spec.error());
    nlohmann::json request = convergenceJobRequestJson(spec.value());
    std::shared_ptr<Renderer> renderer = service.renderer;
    auto run = [renderer, spec = std::move(spec.value())](JobContext& context) {
      return runConvergenceJob(*renderer, spec, context);
    };
    request = submitOnePiece(service, res, who, JobKind::Convergence, std::move(request), std::move(run));
    if (request.is_null()) return;
    request.erase("scene");
    sendJson(res, request, 202);
  });

  server.Post("/api/jobs/fit",
              [&service](const httplib::Request& req, httplib::Response& res) { postFitJob(service, req, res); });

  server.Get("/api/jobs/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string id = req.matches[1];
    if (!jobVisible(service, req, res, id)) return;
    auto job = service.jobs->describe(id);
    if (!job) return sendError(res, ErrorCode::NotFound, "no job '" + id + "'", "id");
    sendJson(res, *job);
  });

  // Cancels a queued or running job and answers it ("cancelled"; a running convergence job
  // stops after its current pass, a BRDF being tested finishes first). A finished job is left as is.
  server.Delete("/api/jobs/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string id = req.matches[1];
    if (!jobVisible(service, req, res, id)) return;
    if (!service.jobs->cancel(id)) return sendError(res, ErrorCode::NotFound, "no job '" + id + "'", "id");
    auto job = service.jobs->describe(id);
    if (!job) return sendError(res, ErrorCode::NotFound, "no job '" + id + "'", "id");
    sendJson(res, *job);
  });
}

}  // namespace brdfa::server
