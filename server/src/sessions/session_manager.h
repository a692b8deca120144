// The set of live sessions. `default` always exists and cannot be deleted. Thread-safe.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "brdfa/renderer.h"
#include "sessions/session.h"

namespace brdfa::server {

inline constexpr const char* kDefaultSessionId = "default";

class SessionManager {
 public:
  // When the cap is reached, create() reclaims the session unused for longest if it has been
  // unused for at least `reclaimAfter` (browser tabs make sessions and cannot reliably delete
  // them: a class would otherwise fill the server with abandoned ones). `default` is never
  // reclaimed.
  // `idPrefix` starts every random id (a replica's "<tag>.", config.h), so a balancer can tell
  // from an id which replica holds the session.
  SessionManager(std::shared_ptr<Renderer> renderer, std::chrono::milliseconds idleTimeout, size_t maxSessions,
                 std::chrono::milliseconds reclaimAfter = std::chrono::minutes(10), std::string idPrefix = {},
                 ServiceMetrics* metrics = nullptr);
  ~SessionManager();  // stopAll()

  struct Created {
    std::shared_ptr<Session> session;  // null when full or on error
    bool full = false;                 // the session cap was reached
    bool quotaFull = false;            // the owner has `ownerLimit` sessions, none abandoned
    size_t ownerSessions = 0;          // with quotaFull: how many the owner has
    std::optional<Error> error;        // createView failed
  };
  // A new session with the given id, or idPrefix + a random 16-hex-digit one when `id` is empty,
  // owned as `ownership` says (its viewKey is made here). With `ownerLimit` > 0 the owner may
  // hold that many: at the limit, their own session unused for longest is reclaimed if it has
  // been unused for `reclaimAfter`, else quotaFull.
  Created create(const std::string& id = {}, SessionOwnership ownership = {}, size_t ownerLimit = 0);

  std::shared_ptr<Session> find(const std::string& id) const;
  std::vector<std::shared_ptr<Session>> list() const;

  enum class RemoveOutcome { Removed, NotFound, Protected };
  // Stops the session (its render thread joins, its streams end) and forgets it.
  RemoveOutcome remove(const std::string& id);

  // Stops every session (server shutdown). New creations fail afterwards.
  void stopAll();

  size_t maxSessions() const { return maxSessions_; }

  // `fn` runs after every create, reclaim and remove, outside the manager's lock (set once,
  // before serving): the replica's session directory republishes from it.
  void onChange(std::function<void()> fn) { onChange_ = std::move(fn); }

 private:
  std::string randomId();

  const std::shared_ptr<Renderer> renderer_;
  const std::chrono::milliseconds idleTimeout_;
  const size_t maxSessions_;
  const std::chrono::milliseconds reclaimAfter_;
  const std::string idPrefix_;
  ServiceMetrics* const metrics_;
  // The non-default session unused for longest (of `owner` only, when given), if unused for at
  // least reclaimAfter_; removed from the map (the caller stops it outside the lock). Holds mutex_.
  std::shared_ptr<Session> takeAbandonedLocked(const std::string* owner = nullptr);
  size_t countOwnedLocked(const std::string& owner) const;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Session>> sessions_;
  bool stopped_ = false;
  std::function<void()> onChange_;
  void changed() const {
    if (onChange_) onChange_();
  }
};

}  // namespace brdfa::server
