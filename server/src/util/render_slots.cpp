#include "util/render_slots.h"

namespace brdfa::server {

bool RenderSlots::acquire(std::chrono::milliseconds timeout, uint64_t units) {
  std::unique_lock lock(mutex_);
  if (units > capacity_ || (free_ < units && waiting_ >= maxWaiting_)) return false;
  ++waiting_;
  const auto start = std::chrono::steady_clock::now();
  bool got = cv_.wait_for(lock, timeout, [&] { return shutdown_ || free_ >= units; });
  --waiting_;
  if (waits_) waits_->add(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!got || shutdown_) return false;
  free_ -= units;
  return true;
}

void RenderSlots::release(uint64_t units) {
  {
    std::lock_guard lock(mutex_);
    free_ += units;
  }
  // Waiters want different amounts: each checks whether it fits now.
  cv_.notify_all();
}

uint64_t RenderSlots::taken() const {
  std::lock_guard lock(mutex_);
  return capacity_ - free_;
}

void RenderSlots::shutdown() {
  {
    std::lock_guard lock(mutex_);
    shutdown_ = true;
  }
  cv_.notify_all();
}

}  // namespace brdfa::server
