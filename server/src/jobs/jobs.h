// Background jobs, off the HTTP threads and the session render threads:
// - batch tests (the thesis's Test Window): compile and numerically check many BRDFs on a small
//   worker pool of its own, one BRDF per task;
// - jobs that run as one piece with progress and cancellation (the convergence comparison of
//   sampling modes), one at a time on a worker of their own: they measure time, so two at once would
//   distort each other, and a long one never holds up the batch tests.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "brdfa/renderer.h"
#include "storage/brdf_library.h"

namespace brdfa::server {

inline constexpr int kJobWorkers = 2;
inline constexpr size_t kMaxJobs = 32;           // kept; the oldest finished job is dropped beyond
inline constexpr size_t kMaxOpenRunnerJobs = 4;  // queued or running one-piece jobs; refused beyond

// One BRDF to test: its definition, or the parse error of a broken saved file.
struct JobItem {
  std::string name;
  std::shared_ptr<const BrdfDefinition> definition;
  std::optional<Error> parseError;
};

// What a one-piece job sees while it runs. Thread-safe.
class JobContext {
 public:
  virtual ~JobContext() = default;
  // True once the job was cancelled (DELETE /api/jobs/{id}) or the server is stopping: the job
  // should return soon (its result is then dropped).
  virtual bool cancelled() const = 0;
  virtual void setProgress(double fraction) = 0;  // 0..1, shown by describe()
  // What the job has so far (a loss curve), shown by describe() as "partial" until it ends.
  virtual void setPartial(nlohmann::json partial) = 0;
};
// The job's work: its result JSON, or an error (state "failed").
using JobRunner = std::function<Result<nlohmann::json>(JobContext&)>;

// Who submits a job, and how many open (queued or running) jobs they may have; 0: no limit.
struct JobOwner {
  std::string user;  // Identity::owner()
  size_t maxOpen = 0;
};

// What submit() did: the new job's id, or why there is none.
struct JobSubmitted {
  std::optional<std::string> id;
  bool quotaFull = false;  // the owner already has maxOpen open jobs
  size_t ownerOpen = 0;    // with quotaFull: how many
};

// What a job does: a batch test of BRDFs, or a one-piece job: a convergence comparison, a fit.
enum class JobKind { Validate, Convergence, Fit };
const char* jobKindName(JobKind kind);  // "validate", "convergence", "fit": the job's "kind"

class JobManager {
 public:
  // Job ids are idPrefix + "job-<n>" (a replica's "<tag>.", config.h).
  explicit JobManager(std::shared_ptr<Renderer> renderer, int workers = kJobWorkers, std::string idPrefix = {});
  ~JobManager();  // stop() and join the workers

  // Queues a batch test; no id when kMaxJobs jobs are all unfinished or the owner is at their limit.
  JobSubmitted submit(std::vector<JobItem> items, const JobOwner& owner = {});

  // Queues a one-piece job of `kind`; `request` is echoed by describe(). No id
  // when kMaxOpenRunnerJobs such jobs are queued or running, kMaxJobs are all unfinished, or the
  // owner is at their limit.
  JobSubmitted submitRunner(JobKind kind, nlohmann::json request, JobRunner run, const JobOwner& owner = {});
  // The owner of a job (JobOwner::user); nullopt for unknown ids.
  std::optional<std::string> ownerOf(const std::string& id) const;

  // Batch tests: {"id", "kind": "validate", "state", "progress", "total", "finished",
  // "results": [...]}. One-piece jobs: {"id", "kind", "state", "progress", "request", and
  // "result" when done, "error" when failed, "partial" while running once the job set one}. States: queued, running,
  // done, failed (one-piece only), cancelled. nullopt for unknown ids.
  std::optional<nlohmann::json> describe(const std::string& id) const;

  // Cancels a job: queued work is dropped, a running one-piece job is told to stop (it returns
  // within a render pass), a BRDF being tested finishes first. false for unknown ids; a finished
  // job stays as it was.
  bool cancel(const std::string& id);

  // Drops queued work, cancels running one-piece jobs and wakes the workers; a BRDF being
  // processed finishes first. Jobs still open stay "running" (or "queued") forever. Safe more
  // than once, from any thread.
  void stop();

 private:
  struct Job {
    std::string id;
    std::string owner;
    JobKind kind = JobKind::Validate;
    std::vector<JobItem> items;
    std::vector<std::optional<nlohmann::json>> results;
    size_t started = 0;
    size_t finished = 0;
    bool cancelled = false;
    // One-piece jobs.
    JobRunner runner;
    nlohmann::json request;
    std::atomic<bool> cancelFlag{false};
    double progress = 0;
    bool running = false;
    bool ended = false;
    std::optional<nlohmann::json> result;
    std::optional<nlohmann::json> partial;
    std::optional<Error> error;
    bool isRunner() const { return static_cast<bool>(runner); }
    bool over() const;  // nothing of it runs or waits any more
  };
  class Context;
  struct Task {
    std::shared_ptr<Job> job;
    size_t index;
  };

  void workerLoop();
  void runnerLoop();
  nlohmann::json runItem(const JobItem& item);
  // Makes room for one more job (drops the oldest finished one at kMaxJobs); false when full.
  bool makeRoomLocked();
  // Whether `owner` may open one more job; sets `out` when not.
  bool ownerHasRoomLocked(const JobOwner& owner, JobSubmitted& out) const;

  std::shared_ptr<Renderer> renderer_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Task> queue_;
  std::deque<std::shared_ptr<Job>> runnerQueue_;
  std::condition_variable runnerCv_;
  std::deque<std::shared_ptr<Job>> jobs_;  // oldest first
  uint64_t nextId_ = 1;
  const std::string idPrefix_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
  std::thread runnerWorker_;
};

}  // namespace brdfa::server
