// The service's own figures for GET /metrics: what the routes and sessions count as
// they work. The exposition (Prometheus text format) is prometheus_text.h; the route gathers
// these with the renderer's counters and the live gauges (sessions, streams, memory).
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

#include "brdfa/duration_histogram.h"

namespace brdfa::server {

class ServiceMetrics {
 public:
  DurationRecorder passTime;                 // one progressive pass of a session (RenderView::renderPass)
  DurationRecorder renderQueueWait;          // a one-shot render or analysis waiting for a render slot
  DurationRecorder uploadQueueWait;          // an upload waiting for a check slot
  std::atomic<uint64_t> samplesRendered{0};  // pixel samples of sessions' passes

  // One answered request: by status, and when it is an error (>= 400), by its JSON error name.
  void countResponse(int status, std::string_view errorName);
  std::map<int, uint64_t> responsesByStatus() const;
  std::map<std::string, uint64_t> rejectionsByReason() const;

 private:
  mutable std::mutex mutex_;
  std::map<int, uint64_t> responses_;
  std::map<std::string, uint64_t, std::less<>> rejections_;
};

}  // namespace brdfa::server
