#include "sessions/session_manager.h"

#include <random>

#include "util/auth_crypto.h"

namespace brdfa::server {

SessionManager::SessionManager(std::shared_ptr<Renderer> renderer, std::chrono::milliseconds idleTimeout,
                               size_t maxSessions, std::chrono::milliseconds reclaimAfter, std::string idPrefix,
                               ServiceMetrics* metrics)
    : renderer_(std::move(renderer)),
      idleTimeout_(idleTimeout),
      maxSessions_(maxSessions),
      reclaimAfter_(reclaimAfter),
      idPrefix_(std::move(idPrefix)),
      metrics_(metrics) {}

std::shared_ptr<Session> SessionManager::takeAbandonedLocked(const std::string* owner) {
  const auto now = Session::Clock::now();
  auto oldest = sessions_.end();
  std::chrono::milliseconds longest{-1};
  for (auto it = sessions_.begin(); it != sessions_.end(); ++it) {
    if (it->first == kDefaultSessionId || (owner && it->second->owner() != *owner)) continue;
    const auto idle = it->second->inactiveFor(now);
    if (idle >= reclaimAfter_ && idle > longest) {
      longest = idle;
      oldest = it;
    }
  }
  if (oldest == sessions_.end()) return nullptr;
  std::shared_ptr<Session> taken = std::move(oldest->second);
  sessions_.erase(oldest);
  return taken;
}

size_t SessionManager::countOwnedLocked(const std::string& owner) const {
  size_t n = 0;
  for (const auto& [id, s] : sessions_) n += id != kDefaultSessionId && s->owner() == owner;
  return n;
}

SessionManager::~SessionManager() { stopAll(); }

std::string SessionManager::randomId() {
  // Unguessable enough that one student cannot stumble into another's session by counting.
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  static const char* hex = "0123456789abcdef";
  uint64_t bits = rng();
  std::string id(16, '0');
  for (int i = 0; i < 16; ++i) id[i] = hex[(bits >> (4 * i)) & 15];
  return id;
}

SessionManager::Created SessionManager::create(const std::string& requestedId, SessionOwnership ownership,
                                               size_t ownerLimit) {
  Created out;
  std::vector<std::shared_ptr<Session>> reclaimed;  // stopped outside the lock (joins threads)
  // Whether a session may be added now; checked before and after the unlocked createView,
  // since another create may fill the last slot (or the server stop) meanwhile. A full server
  // first reclaims an abandoned session, an owner at their limit their own. Holds mutex_.
  auto refused = [&] {
    if (!stopped_ && ownerLimit > 0 && countOwnedLocked(ownership.user) >= ownerLimit)
      if (auto abandoned = takeAbandonedLocked(&ownership.user)) reclaimed.push_back(std::move(abandoned));
    if (!stopped_ && ownerLimit > 0 && (out.ownerSessions = countOwnedLocked(ownership.user)) >= ownerLimit) {
      out.quotaFull = true;
      return true;
    }
    if (!stopped_ && sessions_.size() >= maxSessions_)
      if (auto abandoned = takeAbandonedLocked()) reclaimed.push_back(std::move(abandoned));
    if (stopped_)
      out.error = makeError(ErrorCode::DeviceError, "server is shutting down");
    else if (sessions_.size() >= maxSessions_)
      out.full = true;
    return stopped_ || out.full;
  };
  bool reclaimedAny = false;
  auto stopReclaimed = [&] {
    for (auto& s : reclaimed) s->stop();
    reclaimedAny = reclaimedAny || !reclaimed.empty();
    reclaimed.clear();
  };
  bool refusedNow;
  {
    std::lock_guard lock(mutex_);
    refusedNow = refused();
  }
  stopReclaimed();
  if (refusedNow) {
    if (reclaimedAny) changed();
    return out;
  }
  // createView may allocate device memory; not under the lock.
  Result<std::unique_ptr<RenderView>> view = renderer_->createView();
  if (!view) {
    out.error = view.takeError();
    if (reclaimedAny) changed();
    return out;
  }
  {
    std::lock_guard lock(mutex_);
    refusedNow = refused();
    if (!refusedNow) {
      std::string id = requestedId;
      while (id.empty() || sessions_.count(id)) id = idPrefix_ + randomId();
      ownership.viewKey = randomBase64Url(16);
      auto session =
          std::make_shared<Session>(id, std::move(view.value()), idleTimeout_, metrics_, std::move(ownership));
      sessions_[id] = session;
      out.session = std::move(session);
    }
  }
  stopReclaimed();
  if (out.session || reclaimedAny) changed();
  return out;
}

std::shared_ptr<Session> SessionManager::find(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(id);
  return it == sessions_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<Session>> SessionManager::list() const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<Session>> out;
  for (const auto& [id, s] : sessions_) out.push_back(s);
  return out;
}

SessionManager::RemoveOutcome SessionManager::remove(const std::string& id) {
  if (id == kDefaultSessionId) return RemoveOutcome::Protected;
  std::shared_ptr<Session> session;
  {
    std::lock_guard lock(mutex_);
    auto it = sessions_.find(id);
    if (it == sessions_.end()) return RemoveOutcome::NotFound;
    session = std::move(it->second);
    sessions_.erase(it);
  }
  // Outside the lock: joining the render thread may wait for one pass.
  session->stop();
  changed();
  return RemoveOutcome::Removed;
}

void SessionManager::stopAll() {
  std::vector<std::shared_ptr<Session>> all;
  {
    std::lock_guard lock(mutex_);
    stopped_ = true;
    for (const auto& [id, s] : sessions_) all.push_back(s);
  }
  for (auto& s : all) s->stop();
}

}  // namespace brdfa::server
