// A histogram of durations with fixed bucket bounds, shared by every timed figure the service
// exports (GET /metrics): compiles here in the renderer, passes and queue waits in the server.
// Fixed bounds make histograms from different processes (a restarted render worker) add up.
#pragma once

#include <array>
#include <cstdint>
#include <mutex>

namespace brdfa {

struct DurationHistogram {
  // Upper bounds in seconds: 1 ms (a cached pipeline, an idle queue) to 10 s (a pass at its
  // budget, a slow compile); anything longer lands in the +Inf bucket.
  static constexpr std::array<double, 13> kBoundsSec{0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1,
                                                     0.25,  0.5,    1.0,   2.5,  5.0,   10.0};
  // counts[i]: observations in (kBoundsSec[i-1], kBoundsSec[i]]; the last one is above every bound.
  std::array<uint64_t, kBoundsSec.size() + 1> counts{};
  double sumSec = 0;
  uint64_t count = 0;

  void add(double seconds) {
    size_t i = 0;
    while (i < kBoundsSec.size() && !(seconds <= kBoundsSec[i])) ++i;  // NaN goes to +Inf
    ++counts[i];
    ++count;
    if (seconds == seconds) sumSec += seconds;
  }
  void merge(const DurationHistogram& other) {
    for (size_t i = 0; i < counts.size(); ++i) counts[i] += other.counts[i];
    sumSec += other.sumSec;
    count += other.count;
  }
};

// A DurationHistogram that many threads add to.
class DurationRecorder {
 public:
  void add(double seconds) {
    std::lock_guard lock(mutex_);
    histogram_.add(seconds);
  }
  DurationHistogram snapshot() const {
    std::lock_guard lock(mutex_);
    return histogram_;
  }

 private:
  mutable std::mutex mutex_;
  DurationHistogram histogram_;
};

}  // namespace brdfa
