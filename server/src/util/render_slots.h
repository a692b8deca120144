// A counting semaphore with bounded waits: one-shot render slots, upload checks and the
// uploads' share of the memory budget.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>

#include "brdfa/duration_histogram.h"

namespace brdfa::server {

// A counting semaphore (of slots, or of bytes) whose waiters give up on timeout or shutdown.
class RenderSlots {
 public:
  RenderSlots(uint64_t count, int maxWaiting) : capacity_(count), free_(count), maxWaiting_(maxWaiting) {}
  // True when `units` were taken; the caller must release() them. False at once when
  // `maxWaiting` callers already wait or `units` is more than the capacity, else after
  // `timeout` or on shutdown.
  bool acquire(std::chrono::milliseconds timeout, uint64_t units = 1);
  void release(uint64_t units = 1);
  void shutdown();
  uint64_t capacity() const { return capacity_; }
  uint64_t taken() const;
  // Every acquire()'s wait, taken or not, is added to `waits` (set once, before use).
  void recordWaitsIn(DurationRecorder* waits) { waits_ = waits; }

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  const uint64_t capacity_;
  uint64_t free_;
  const int maxWaiting_;
  int waiting_ = 0;
  bool shutdown_ = false;
  DurationRecorder* waits_ = nullptr;
};

}  // namespace brdfa::server
