#include "core/memory_ledger.h"

#include <algorithm>
#include <cstdio>

namespace brdfa {

namespace {
const char* useName(MemoryUse use) {
  switch (use) {
    case MemoryUse::Fixed: return "the device process";
    case MemoryUse::RenderTargets: return "render targets";
    case MemoryUse::Assets: return "meshes, textures and environments";
    case MemoryUse::Transfers: return "uploads to the device";
    case MemoryUse::Programs: return "compiled programs";
    case MemoryUse::Compiles: return "compiles";
    default: return "memory";
  }
}
}  // namespace

std::string mebibytesText(uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f MiB", double(bytes) / (1024.0 * 1024.0));
  return text;
}

bool MemoryLedger::tryExchange(MemoryUse use, uint64_t oldBytes, uint64_t newBytes) {
  uint64_t total = total_.load();
  do {
    const uint64_t others = total - std::min(total, oldBytes);
    if (budget_ && newBytes > oldBytes && others + newBytes > budget_) return false;
  } while (!total_.compare_exchange_weak(total, total - std::min(total, oldBytes) + newBytes));
  auto& used = used_[size_t(use)];
  uint64_t u = used.load();
  while (!used.compare_exchange_weak(u, u - std::min(u, oldBytes) + newBytes)) {
  }
  return true;
}

Result<void> MemoryLedger::exchange(MemoryUse use, uint64_t oldBytes, uint64_t newBytes, const std::string& what,
                                    const Shrink& shrink, std::string* dropped) {
  if (tryExchange(use, oldBytes, newBytes)) return {};
  if (shrink) {
    const uint64_t total = total_.load();
    const uint64_t wanted = total - std::min(total, oldBytes) + newBytes;
    std::string gone = shrink(wanted > budget_ ? wanted - budget_ : 0);
    const bool fits = tryExchange(use, oldBytes, newBytes);
    if (fits && dropped) *dropped = gone;
    if (fits) return {};
  }
  const uint64_t total = total_.load();
  const uint64_t others = total - std::min(total, oldBytes);
  return makeError(ErrorCode::OverBudget,
                   what + " needs " + mebibytesText(newBytes) + " of " + useName(use) + ", and " +
                       (label_.empty() ? "the renderer's memory budget (" + mebibytesText(budget_) + ")" : label_) +
                       " has " + mebibytesText(budget_ - std::min(others, budget_)) +
                       (shrink ? " left after dropping every unused cached program and asset" : " left") +
                       ": use a smaller render size, or close other sessions");
}

void MemoryLedger::release(MemoryUse use, uint64_t bytes) { (void)tryExchange(use, bytes, 0); }

void MemoryLedger::add(MemoryUse use, uint64_t bytes) {
  total_ += bytes;
  used_[size_t(use)] += bytes;
}

void MemoryLedger::noteDropped(uint64_t bytes, const std::string& what) {
  std::lock_guard lock(droppedMutex_);
  droppedBytes_ += bytes;
  ++drops_;
  lastDropped_ = what;
}

MemoryUsage MemoryLedger::usage() const {
  MemoryUsage u;
  u.budget = budget_;
  u.fixed = used_[size_t(MemoryUse::Fixed)].load();
  u.renderTargets = used_[size_t(MemoryUse::RenderTargets)].load();
  u.assets = used_[size_t(MemoryUse::Assets)].load();
  u.transfers = used_[size_t(MemoryUse::Transfers)].load();
  u.programs = used_[size_t(MemoryUse::Programs)].load();
  u.compiles = used_[size_t(MemoryUse::Compiles)].load();
  std::lock_guard lock(droppedMutex_);
  u.droppedBytes = droppedBytes_;
  u.drops = drops_;
  u.lastDropped = lastDropped_;
  return u;
}

}  // namespace brdfa
