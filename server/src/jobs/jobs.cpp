#include "jobs/jobs.h"

#include <algorithm>
#include <chrono>

#include "http/http_errors.h"

namespace brdfa::server {

namespace {

using json = nlohmann::json;

std::string diagnosticText(const Diagnostic& d) {
  return d.line > 0 ? "line " + std::to_string(d.line) + ": " + d.message : d.message;
}

// The error's message plus one line per diagnostic.
void appendError(json& log, const Error& e) {
  log.push_back(e.message);
  for (const Diagnostic& d : e.diagnostics) log.push_back(diagnosticText(d));
}

int errorCount(const Error& e) { return e.diagnostics.empty() ? 1 : static_cast<int>(e.diagnostics.size()); }

// Each property a file may claim: claimed or not, whether it holds, and the measurement.
json claimsJson(const std::vector<ClaimVerdict>& claims) {
  json out = json::array();
  for (const ClaimVerdict& c : claims)
    out.push_back({{"name", c.name}, {"claimed", c.claimed}, {"holds", c.holds}, {"measured", c.measured}});
  return out;
}

}  // namespace

bool JobManager::Job::over() const {
  if (isRunner()) return ended;
  return finished == items.size() || (cancelled && started == finished);
}

class JobManager::Context : public JobContext {
 public:
  Context(JobManager& m, Job& job) : m_(m), job_(job) {}
  bool cancelled() const override { return job_.cancelFlag.load(); }
  void setProgress(double fraction) override {
    std::lock_guard lock(m_.mutex_);
    job_.progress = std::clamp(fraction, 0.0, 1.0);
  }
  void setPartial(json partial) override {
    std::lock_guard lock(m_.mutex_);
    job_.partial = std::move(partial);
  }

 private:
  JobManager& m_;
  Job& job_;
};

const char* jobKindName(JobKind kind) {
  switch (kind) {
    case JobKind::Convergence: return "convergence";
    case JobKind::Fit: return "fit";
    case JobKind::Validate: break;
  }
  return "validate";
}

JobManager::JobManager(std::shared_ptr<Renderer> renderer, int workers, std::string idPrefix)
    : renderer_(std::move(renderer)), idPrefix_(std::move(idPrefix)) {
  for (int i = 0; i < workers; ++i) workers_.emplace_back([this] { workerLoop(); });
  runnerWorker_ = std::thread([this] { runnerLoop(); });
}

JobManager::~JobManager() {
  stop();
  for (std::thread& t : workers_)
    if (t.joinable()) t.join();
  if (runnerWorker_.joinable()) runnerWorker_.join();
}

void JobManager::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    queue_.clear();
    runnerQueue_.clear();
    for (auto& job : jobs_) job->cancelFlag = true;
  }
  cv_.notify_all();
  runnerCv_.notify_all();
}

bool JobManager::makeRoomLocked() {
  if (jobs_.size() < kMaxJobs) return true;
  auto it = std::find_if(jobs_.begin(), jobs_.end(), [](const std::shared_ptr<Job>& j) { return j->over(); });
  if (it == jobs_.end()) return false;
  jobs_.erase(it);
  return true;
}

bool JobManager::ownerHasRoomLocked(const JobOwner& owner, JobSubmitted& out) const {
  if (owner.maxOpen == 0) return true;
  size_t open = 0;
  for (const auto& j : jobs_) open += j->owner == owner.user && !j->over();
  if (open < owner.maxOpen) return true;
  out.quotaFull = true;
  out.ownerOpen = open;
  return false;
}

std::optional<std::string> JobManager::ownerOf(const std::string& id) const {
  std::lock_guard lock(mutex_);
  for (const auto& j : jobs_)
    if (j->id == id) return j->owner;
  return std::nullopt;
}

JobSubmitted JobManager::submitRunner(JobKind kind, json request, JobRunner run, const JobOwner& owner) {
  JobSubmitted out;
  auto job = std::make_shared<Job>();
  job->owner = owner.user;
  job->kind = kind;
  job->request = std::move(request);
  job->runner = std::move(run);
  {
    std::lock_guard lock(mutex_);
    size_t open = 0;
    for (const auto& j : jobs_) open += j->isRunner() && !j->over();
    if (!ownerHasRoomLocked(owner, out) || open >= kMaxOpenRunnerJobs || !makeRoomLocked()) return out;
    job->id = idPrefix_ + "job-" + std::to_string(nextId_++);
    jobs_.push_back(job);
    if (stopping_) {
      job->cancelFlag = true;
      job->ended = true;
    } else {
      runnerQueue_.push_back(job);
    }
  }
  runnerCv_.notify_all();
  out.id = job->id;
  return out;
}

bool JobManager::cancel(const std::string& id) {
  std::lock_guard lock(mutex_);
  auto it = std::find_if(jobs_.begin(), jobs_.end(), [&](const std::shared_ptr<Job>& j) { return j->id == id; });
  if (it == jobs_.end()) return false;
  const std::shared_ptr<Job>& job = *it;
  if (job->over()) return true;
  job->cancelled = true;
  job->cancelFlag = true;
  if (job->isRunner()) {
    auto queued = std::find(runnerQueue_.begin(), runnerQueue_.end(), job);
    if (queued != runnerQueue_.end()) {
      runnerQueue_.erase(queued);
      job->ended = true;
    }
  } else {
    queue_.erase(std::remove_if(queue_.begin(), queue_.end(), [&](const Task& t) { return t.job == job; }),
                 queue_.end());
  }
  return true;
}

void JobManager::runnerLoop() {
  for (;;) {
    std::shared_ptr<Job> job;
    {
      std::unique_lock lock(mutex_);
      runnerCv_.wait(lock, [&] { return stopping_ || !runnerQueue_.empty(); });
      if (stopping_) return;
      job = std::move(runnerQueue_.front());
      runnerQueue_.pop_front();
      job->running = true;
    }
    Context context(*this, *job);
    Result<json> result = makeError(ErrorCode::Internal, "job did not run");
    try {
      result = job->runner(context);
    } catch (const std::exception& e) {
      result = makeError(ErrorCode::Internal, std::string("job failed: ") + e.what());
    }
    std::lock_guard lock(mutex_);
    job->running = false;
    job->ended = true;
    job->partial.reset();
    if (job->cancelFlag) {
      job->cancelled = true;
    } else if (result) {
      job->result = std::move(result.value());
      job->progress = 1;
    } else {
      job->error = result.takeError();
    }
  }
}

JobSubmitted JobManager::submit(std::vector<JobItem> items, const JobOwner& owner) {
  JobSubmitted out;
  auto job = std::make_shared<Job>();
  job->owner = owner.user;
  job->items = std::move(items);
  job->results.resize(job->items.size());
  {
    std::lock_guard lock(mutex_);
    if (!ownerHasRoomLocked(owner, out) || !makeRoomLocked()) return out;
    job->id = idPrefix_ + "job-" + std::to_string(nextId_++);
    jobs_.push_back(job);
    if (!stopping_)
      for (size_t i = 0; i < job->items.size(); ++i) queue_.push_back(Task{job, i});
  }
  cv_.notify_all();
  out.id = job->id;
  return out;
}

std::optional<json> JobManager::describe(const std::string& id) const {
  std::lock_guard lock(mutex_);
  for (const auto& job : jobs_) {
    if (job->id != id) continue;
    if (job->isRunner()) {
      const char* state = job->cancelled ? "cancelled"
                          : job->result  ? "done"
                          : job->error   ? "failed"
                          : job->running ? "running"
                                         : "queued";
      json out{{"id", job->id},
               {"kind", jobKindName(job->kind)},
               {"state", state},
               {"progress", job->progress},
               {"request", job->request}};
      if (job->result) out["result"] = *job->result;
      if (job->partial && !job->ended && !job->cancelled) out["partial"] = *job->partial;
      if (job->error) {
        out["error"] = {{"error", errorCodeName(job->error->code)}, {"message", job->error->message}};
        if (!job->error->field.empty()) out["error"]["field"] = job->error->field;
        if (!job->error->diagnostics.empty()) out["error"]["diagnostics"] = diagnosticsToJson(job->error->diagnostics);
      }
      return out;
    }
    size_t total = job->items.size();
    const char* state = job->finished == total          ? "done"
                        : job->cancelled && job->over() ? "cancelled"
                        : job->started == 0             ? "queued"
                                                        : "running";
    json results = json::array();
    for (const auto& r : job->results)
      if (r) results.push_back(*r);
    return json{{"id", job->id},
                {"kind", jobKindName(job->kind)},
                {"state", state},
                {"progress", total == 0 ? 1.0 : static_cast<double>(job->finished) / static_cast<double>(total)},
                {"total", total},
                {"finished", job->finished},
                {"results", results}};
  }
  return std::nullopt;
}

void JobManager::workerLoop() {
  for (;;) {
    Task task;
    {
      std::unique_lock lock(mutex_);
      cv_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      task = std::move(queue_.front());
      queue_.pop_front();
      ++task.job->started;
    }
    json result = runItem(task.job->items[task.index]);
    std::lock_guard lock(mutex_);
    task.job->results[task.index] = std::move(result);
    ++task.job->finished;
  }
}

json JobManager::runItem(const JobItem& item) {
  json out{{"name", item.name}, {"ok", false}, {"errors", 0}, {"log", json::array()}, {"compile_ms", 0.0}};
  json& log = out["log"];
  if (!item.definition) {
    const Error& e = item.parseError ? *item.parseError : Error{ErrorCode::Internal, "no definition", {}, {}};
    appendError(log, e);
    out["errors"] = errorCount(e);
    out["checks"] = {{"error", "not run: the BRDF did not parse"}};
    return out;
  }
  for (const Diagnostic& d : item.definition->warnings) log.push_back("warning: " + diagnosticText(d));

  auto t0 = std::chrono::steady_clock::now();
  Result<CompileInfo> compiled = renderer_->compileBrdf(*item.definition);
  double wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!compiled) {
    appendError(log, compiled.error());
    out["errors"] = errorCount(compiled.error());
    out["compile_ms"] = wallMs;
    out["checks"] = {{"error", "not run: the BRDF did not compile"}};
    return out;
  }
  out["compile_ms"] = compiled->compileMs;
  out["cached"] = compiled->cached;
  for (const Diagnostic& d : compiled->warnings) log.push_back("warning: " + diagnosticText(d));

  Result<BrdfCheckReport> checked = renderer_->checkBrdf(*item.definition);
  bool ok = true;
  if (checked) {
    const BrdfCheckReport& r = checked.value();
    out["checks"] = {
        {"nan", r.nanCount},
        {"inf", r.infCount},
        {"negative", r.negativeCount},
        {"max_albedo", r.maxAlbedo},
        {"max_albedo_std_error", r.maxAlbedoStdError},
        {"albedo_above_one", r.albedoAboveOne},
        {"max_reciprocity_error", r.maxReciprocityError},
        {"evaluations", r.evaluations},
        {"left_out", r.leftOut},
        {"worst", {{"reciprocity", r.worstReciprocity}, {"bad_value", r.firstBadValue}, {"albedo", r.worstAlbedo}}},
        {"claims", claimsJson(r.claims)},
        {"claims_declared", item.definition->claims.declared},
        {"ms", r.ms}};
    ok = r.ok();
    for (const ClaimVerdict& c : r.claims)
      if (c.claimed && !c.holds) log.push_back("check: claim '" + c.name + "' violated: " + c.measured);
    if (!item.definition->claims.declared)
      log.push_back("check: the file declares no claims (a '# claims: ...' line): properties are reported, not failed");
    if (r.nanCount) log.push_back("check: " + std::to_string(r.nanCount) + " NaN values");
    if (r.infCount) log.push_back("check: " + std::to_string(r.infCount) + " infinite values");
    if (r.negativeCount) log.push_back("check: " + std::to_string(r.negativeCount) + " negative values");
    // Where: each finding's worst (or first) case, so a failure can be reproduced.
    if (!r.firstBadValue.empty()) log.push_back("check: first bad value: " + r.firstBadValue);
    if (!r.worstReciprocity.empty()) log.push_back("check: worst reciprocity error " + r.worstReciprocity);
    if (!r.worstAlbedo.empty()) log.push_back("check: largest albedo " + r.worstAlbedo);
    if (r.leftOut)
      log.push_back("check: " + std::to_string(r.leftOut) +
                    " (L, V) pairs with L = -V on the horizon left out (measure zero; the half vector is 0/0)");
  } else {
    // The check could not run (Unsupported for a legacy render() file, rendered but never
    // analysed): reported, and not held against the BRDF unless it found a compile error.
    const Error& e = checked.error();
    out["checks"] = {{"error", errorCodeName(e.code)}, {"message", e.message}};
    log.push_back("check: " + e.message);
    if (e.code == ErrorCode::CompileError) {
      ok = false;
      out["errors"] = errorCount(e);
    }
  }
  out["ok"] = ok;
  return out;
}

}  // namespace brdfa::server
