// Batch test jobs (the thesis's Test Window): compile and numerically check many BRDFs on a small
// worker pool of its own, off the HTTP threads and the session render threads.
#pragma once

#include <condition_variable>
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
#include "brdfa_server/brdf_library.h"

namespace brdfa::server {

inline constexpr int kJobWorkers = 2;
inline constexpr size_t kMaxJobs = 32;  // kept; the oldest finished job is dropped beyond

// One BRDF to test: its definition, or the parse error of a broken saved file.
struct JobItem {
  std::string name;
  std::shared_ptr<const BrdfDefinition> definition;
  std::optional<Error> parseError;
};

class JobManager {
 public:
  explicit JobManager(std::shared_ptr<Renderer> renderer, int workers = kJobWorkers);
  ~JobManager();  // stop() and join the workers

  // Queues a job; returns its id, or nullopt when kMaxJobs jobs are all unfinished.
  std::optional<std::string> submit(std::vector<JobItem> items);

  // {"id", "state", "progress", "total", "finished", "results": [...]}; nullopt for unknown ids.
  std::optional<nlohmann::json> describe(const std::string& id) const;

  // Drops queued work and wakes the workers; a BRDF being processed finishes first. Jobs still
  // open stay "running" (or "queued") forever. Safe more than once, from any thread.
  void stop();

 private:
  struct Job {
    std::string id;
    std::vector<JobItem> items;
    std::vector<std::optional<nlohmann::json>> results;
    size_t started = 0;
    size_t finished = 0;
  };
  struct Task {
    std::shared_ptr<Job> job;
    size_t index;
  };

  void workerLoop();
  nlohmann::json runItem(const JobItem& item);

  std::shared_ptr<Renderer> renderer_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Task> queue_;
  std::deque<std::shared_ptr<Job>> jobs_;  // oldest first
  uint64_t nextId_ = 1;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace brdfa::server
