// Device work in flight, by the request it serves: what a watchdog needs to tell which request
// holds the device. The render worker tags each request's thread; the renderer
// opens a Scope around every queue submission (until its fence signals) and every pipeline
// build (the driver's shader compile). The queue runs submissions in order, so the oldest
// submission in flight is the one running or the one every later submission waits behind.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>

namespace brdfa::device_activity {

enum class Kind { Submission, PipelineBuild };

// The tag of the calling thread's work (0: untagged, e.g. in-process renderers).
void setThreadTag(uint64_t tag);

struct Entry {
  uint64_t tag = 0;
  Kind kind = Kind::Submission;
  std::chrono::steady_clock::time_point start;
  double cpuStart = 0;  // processCpuSeconds() at start
};

// CPU time this process has used so far, all threads (CLOCK_PROCESS_CPUTIME_ID), in seconds.
// On a CPU device (lavapipe) the device's work is this process's CPU time, which a loaded
// machine does not inflate the way it inflates wall time.
double processCpuSeconds();

// Registers the calling thread's work from construction to destruction.
class Scope {
 public:
  explicit Scope(Kind kind);
  ~Scope();
  Scope(const Scope&) = delete;
  Scope& operator=(const Scope&) = delete;

 private:
  uint64_t key_;
};

// The longest-running work now in flight, if any.
std::optional<Entry> oldest();
// The longest-running work of one kind now in flight, if any.
std::optional<Entry> oldest(Kind kind);

}  // namespace brdfa::device_activity
