#include "brdfa_server/jobs.h"

#include <algorithm>
#include <chrono>

#include "brdfa_server/http_errors.h"

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

}  // namespace

JobManager::JobManager(std::shared_ptr<Renderer> renderer, int workers) : renderer_(std::move(renderer)) {
  for (int i = 0; i < workers; ++i) workers_.emplace_back([this] { workerLoop(); });
}

JobManager::~JobManager() {
  stop();
  for (std::thread& t : workers_)
    if (t.joinable()) t.join();
}

void JobManager::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    queue_.clear();
  }
  cv_.notify_all();
}

std::optional<std::string> JobManager::submit(std::vector<JobItem> items) {
  auto job = std::make_shared<Job>();
  job->items = std::move(items);
  job->results.resize(job->items.size());
  {
    std::lock_guard lock(mutex_);
    if (jobs_.size() >= kMaxJobs) {
      auto it = std::find_if(jobs_.begin(), jobs_.end(),
                             [](const std::shared_ptr<Job>& j) { return j->finished == j->items.size(); });
      if (it == jobs_.end()) return std::nullopt;
      jobs_.erase(it);
    }
    job->id = "job-" + std::to_string(nextId_++);
    jobs_.push_back(job);
    if (!stopping_)
      for (size_t i = 0; i < job->items.size(); ++i) queue_.push_back(Task{job, i});
  }
  cv_.notify_all();
  return job->id;
}

std::optional<json> JobManager::describe(const std::string& id) const {
  std::lock_guard lock(mutex_);
  for (const auto& job : jobs_) {
    if (job->id != id) continue;
    size_t total = job->items.size();
    const char* state = job->finished == total ? "done" : job->started == 0 ? "queued" : "running";
    json results = json::array();
    for (const auto& r : job->results)
      if (r) results.push_back(*r);
    return json{{"id", job->id},
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
    out["checks"] = {{"nan", r.nanCount},
                     {"inf", r.infCount},
                     {"negative", r.negativeCount},
                     {"max_albedo", r.maxAlbedo},
                     {"albedo_above_one", r.albedoAboveOne},
                     {"max_reciprocity_error", r.maxReciprocityError},
                     {"evaluations", r.evaluations},
                     {"ms", r.ms}};
    ok = r.ok();
    if (r.nanCount) log.push_back("check: " + std::to_string(r.nanCount) + " NaN values");
    if (r.infCount) log.push_back("check: " + std::to_string(r.infCount) + " infinite values");
    if (r.negativeCount) log.push_back("check: " + std::to_string(r.negativeCount) + " negative values");
  } else {
    // The check could not run (Unsupported for a legacy render() file, rendered but never
    // analysed): reported, and not held against the BRDF unless it found a compile error.
    const Error& e = checked.error();
    out["checks"] = {{"error", errorName(e.code)}, {"message", e.message}};
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
