#include "device/device_activity.h"

#include <time.h>

#include <map>
#include <mutex>

namespace brdfa::device_activity {
namespace {

std::mutex mutex;
std::map<uint64_t, Entry> inFlight;  // by key, in start order
uint64_t nextKey = 1;
thread_local uint64_t tagOfThread = 0;

}  // namespace

void setThreadTag(uint64_t tag) { tagOfThread = tag; }

double processCpuSeconds() {
  timespec t{};
  if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t) != 0) return 0;  // guard: never fails on Linux
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

Scope::Scope(Kind kind) {
  const double cpu = processCpuSeconds();
  std::lock_guard lock(mutex);
  key_ = nextKey++;
  inFlight.emplace(key_, Entry{tagOfThread, kind, std::chrono::steady_clock::now(), cpu});
}

Scope::~Scope() {
  std::lock_guard lock(mutex);
  inFlight.erase(key_);
}

std::optional<Entry> oldest() {
  std::lock_guard lock(mutex);
  if (inFlight.empty()) return std::nullopt;
  return inFlight.begin()->second;
}

std::optional<Entry> oldest(Kind kind) {
  std::lock_guard lock(mutex);
  for (const auto& [key, entry] : inFlight)
    if (entry.kind == kind) return entry;
  return std::nullopt;
}

}  // namespace brdfa::device_activity
