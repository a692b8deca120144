// One memory budget for everything the renderer holds: what each use takes is
// reserved here before it is allocated, and a reservation that would pass the budget first
// asks the renderer to drop what is optional (unused cached programs and assets), then fails
// with OverBudget naming what asked and what is left. No Vulkan here.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

#include "brdfa/renderer.h"
#include "brdfa/result.h"

namespace brdfa {

enum class MemoryUse {
  Fixed,          // the device process as it starts (driver, fixed pipelines), and its spare copy
  RenderTargets,  // views: G-buffers, accumulators, outputs
  Assets,         // meshes, textures and environments on the device
  Transfers,      // uploads in flight to the device: decoded data and staging buffers
  Programs,       // built pipelines (an estimate each) and the in-memory SPIR-V cache
  Compiles,       // what the compile workers may grow to, at their budget (CompileBudget)
  Count
};

class MemoryLedger {
 public:
  // Drops what is optional until at least `needed` bytes are given back, or nothing optional is
  // left; returns what it dropped, for a person ("2 cached programs (8 MiB)"), empty if nothing.
  using Shrink = std::function<std::string(uint64_t needed)>;

  // `label` names the budget in messages ("the server's memory budget (--max-memory 512 MiB)");
  // empty: "the renderer's memory budget (N MiB)".
  MemoryLedger(uint64_t budget, std::string label) : budget_(budget), label_(std::move(label)) {}
  uint64_t budget() const { return budget_; }  // 0: no budget

  // Replaces a reservation of `oldBytes` under `use` by `newBytes` in one step. When that would
  // pass the budget, calls `shrink` (if given) once and tries again; if it still does not fit,
  // changes nothing and fails with OverBudget ("<what> needs N MiB of <use>, and ... has M MiB
  // left"). Giving back (newBytes <= oldBytes) never fails. On success, what `shrink` dropped
  // (if anything) is in `*dropped`.
  Result<void> exchange(MemoryUse use, uint64_t oldBytes, uint64_t newBytes, const std::string& what,
                        const Shrink& shrink = {}, std::string* dropped = nullptr);
  Result<void> reserve(MemoryUse use, uint64_t bytes, const std::string& what, const Shrink& shrink = {},
                       std::string* dropped = nullptr) {
    return exchange(use, 0, bytes, what, shrink, dropped);
  }
  void release(MemoryUse use, uint64_t bytes);
  // Counts `bytes` whatever the budget says: what is already allocated (the process at start).
  void add(MemoryUse use, uint64_t bytes);

  MemoryUsage usage() const;  // a snapshot of every use, the budget, and what was dropped
  void noteDropped(uint64_t bytes, const std::string& what);

 private:
  bool tryExchange(MemoryUse use, uint64_t oldBytes, uint64_t newBytes);
  const uint64_t budget_;
  const std::string label_;
  std::atomic<uint64_t> total_{0};
  std::array<std::atomic<uint64_t>, size_t(MemoryUse::Count)> used_{};
  mutable std::mutex droppedMutex_;
  uint64_t droppedBytes_ = 0, drops_ = 0;
  std::string lastDropped_;
};

// A reservation given back when it is destroyed: held by what it pays for (a cached program,
// an uploaded asset, a transfer's scope). Default: holds nothing.
class MemoryReservation {
 public:
  MemoryReservation() = default;
  MemoryReservation(MemoryLedger* ledger, MemoryUse use, uint64_t bytes) : ledger_(ledger), use_(use), bytes_(bytes) {}
  MemoryReservation(MemoryReservation&& o) noexcept { *this = std::move(o); }
  MemoryReservation& operator=(MemoryReservation&& o) noexcept {
    if (this != &o) {
      reset();
      ledger_ = o.ledger_;
      use_ = o.use_;
      bytes_ = o.bytes_;
      o.ledger_ = nullptr;
      o.bytes_ = 0;
    }
    return *this;
  }
  ~MemoryReservation() { reset(); }
  void reset() {
    if (ledger_ && bytes_) ledger_->release(use_, bytes_);
    ledger_ = nullptr;
    bytes_ = 0;
  }
  uint64_t bytes() const { return bytes_; }

 private:
  MemoryLedger* ledger_ = nullptr;
  MemoryUse use_ = MemoryUse::Fixed;
  uint64_t bytes_ = 0;
};

// Which of the renderer's cache locks the caller of a shrink holds: the shrink takes the others
// only if they are free, so it never waits and never deadlocks.
struct HeldCacheLocks {
  bool programs = false, assets = false;
};
// The renderer's shrink (drops unused cached programs and assets), for a caller holding `held`.
using CacheShrinker = std::function<MemoryLedger::Shrink(HeldCacheLocks held)>;

// Runs `body` under `m`: at once when the caller holds it, else only if `m` is free (a shrink
// never waits for a lock).
template <class Body>
void underFreeLock(std::mutex& m, bool heldByCaller, Body&& body) {
  if (heldByCaller) return body();
  std::unique_lock lock(m, std::try_to_lock);
  if (lock.owns_lock()) body();
}

// "12 MiB": how the ledger's messages write sizes.
std::string mebibytesText(uint64_t bytes);

}  // namespace brdfa
