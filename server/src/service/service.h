// Everything the routes share: the renderer, the BRDF library, the sessions and the limits.
// Routes hold a reference to one Service; it outlives the HTTP server's worker threads.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "auth/authenticator.h"
#include "auth/identity.h"
#include "brdfa/renderer.h"
#include "config/config.h"
#include "http/static_files.h"
#include "jobs/jobs.h"
#include "json/scene_json.h"
#include "metrics/metrics.h"
#include "sessions/session_directory.h"
#include "sessions/session_manager.h"
#include "storage/asset_store.h"
#include "storage/brdf_catalog.h"
#include "storage/hot_load.h"
#include "util/render_slots.h"

namespace brdfa::server {

class ConnectionRegistry;

// Limits that keep one client from starving the others (docs/design.md section 6); --max-sessions
// sets the session cap.
inline constexpr int kMaxStreams = 48;                      // concurrent stream clients; 503 beyond
inline constexpr int kMaxConcurrentRenders = 2;             // one-shot renders at once
inline constexpr std::chrono::seconds kRenderSlotWait{30};  // then 503 busy
inline constexpr std::chrono::seconds kFrameWait{60};       // min_spp wait bound
inline constexpr int kMaxOneShotSpp = 65536;
inline constexpr int kMaxQueuedRenders = 8;                   // waiting for a slot; 503 beyond
inline constexpr int kMaxConcurrentUploadChecks = 2;          // uploads decoded by inspectAsset at once
inline constexpr int kMaxQueuedUploadChecks = 8;              // waiting for one; 503 beyond
inline constexpr std::chrono::seconds kUploadMemoryWait{30};  // for room in the uploads' share; then 503
// Room for the multipart framing around a file of --max-upload-bytes (boundaries, part
// headers, the `kind` field): the HTTP payload limit is max-upload-bytes plus this.
inline constexpr size_t kMultipartOverhead = 1u << 20;

// Things each person holds at once (one-shot renders in flight), counted per owner. Thread-safe.
class OwnerCounter {
 public:
  // Takes one for `owner` unless they hold `limit` already (0: no limit); `held` gets how many
  // they hold (before this one).
  bool take(const std::string& owner, int limit, int& held);
  void release(const std::string& owner);

 private:
  std::mutex mutex_;
  std::map<std::string, int> held_;
};

// May `who` read BRDF `entry`? Built-ins, the course's and shared ones are everyone's.
inline bool canReadBrdf(const Identity& who, const BrdfEntry& entry) {
  return canRead(who, entry.owner, entry.builtin || entry.owner.empty() || entry.shared);
}
inline bool canReadBrdf(const Identity& who, const BrokenBrdf& broken) {
  return canRead(who, broken.owner, broken.owner.empty() || broken.shared);
}

struct Service {
  // Opens the device, loads the built-in and saved user BRDFs (parsed only) and sets up the `default` session (its
  // scene is applied lazily, on first use). `log` receives start-up warnings.
  static Result<std::unique_ptr<Service>> create(const ServerConfig& config, std::vector<std::string>& log);

  // The largest request body the HTTP layer reads: a JSON body or an upload with its framing.
  size_t maxRequestBody() const;

  // Name resolution for scene JSON of `who`: the BRDFs and uploads they may read;
  // `inlineBrdf` enables objects with "brdf": "inline".
  SceneResolver resolver(const Identity& who, std::shared_ptr<const BrdfDefinition> inlineBrdf = nullptr);
  // The BRDF `name` as `who` may read it: a library file they may read, or a measured upload
  // they may see (its asset id); null otherwise, exactly as for a name that does not exist.
  std::shared_ptr<const BrdfEntry> readableBrdf(const Identity& who, std::string_view name);

  // A quota of `who` (config.quotas' field): 0 (no limit) for the teacher.
  template <class T>
  T quotaFor(const Identity& who, T Quotas::*field) const {
    return who.teacher() ? T(0) : config.quotas.*field;
  }

  // Wakes every waiter and stops every session: streams end, frame waits return, one-shot
  // renders abort between passes.
  void beginShutdown();

  ServerConfig config;
  // Before everything that counts into it (sessions, slots).
  ServiceMetrics metrics;
  // "<replica>." with --replica, else empty: the start of session and job ids.
  std::string idPrefix() const { return config.replica.empty() ? std::string() : config.replica + "."; }
  std::shared_ptr<Renderer> renderer;   // declared before sessions: views die before the device
  std::unique_ptr<Authenticator> auth;  // who a request acts for (--auth)
  BrdfCatalog brdfs;                    // built-ins, the course's and every student's
  OwnerCounter rendersInFlight;         // one-shot renders and analyses, per person (--quota-renders)
  RenderSlots uploadSlots{kMaxConcurrentUploadChecks, kMaxQueuedUploadChecks};
  // Upload bodies in flight, in bytes: their share of --max-memory (memoryBudgetBytes / 8), the
  // renderer has the rest.
  std::unique_ptr<RenderSlots> uploadMemory;
  uint64_t memoryBudgetBytes = 0;      // --max-memory, or half the RAM
  std::unique_ptr<AssetStore> assets;  // uploads and Blender worlds, registered with the renderer
  std::unique_ptr<SessionManager> sessions;
  // With --replica: the sessions of every replica on this data folder (after `sessions`, so it
  // stops first).
  std::unique_ptr<SessionDirectory> directory;
  std::unique_ptr<JobManager> jobs;  // batch tests; its workers stop in beginShutdown
  HotLoader hotLoader;               // --hot-load; stops in beginShutdown
  StaticFiles staticFiles;           // <root>/web, cached per file version with a gzip copy
  RenderSlots renderSlots{kMaxConcurrentRenders, kMaxQueuedRenders};
  // Requests that hold an HTTP worker for long (streams, frame waits) are capped below the
  // worker count so that short requests (stats, scene edits, health) always find a worker.
  int maxStreams = kMaxStreams;
  int maxFrameWaiters = 16;
  std::atomic<int> activeStreams{0};
  std::atomic<int> frameWaiters{0};
  std::atomic<bool> stopping{false};
  // SIGTERM with --drain-seconds: new sessions and jobs get 503 `draining`, /api/ready 503; the
  // rest is served until the drain ends (HttpServer::drain).
  std::atomic<bool> draining{false};
  // The HTTP front's open connections (set by HttpServer; null without one): a long handler
  // asks it whether its client went away.
  const ConnectionRegistry* connections = nullptr;
};

// The scene of the `default` session: one GGX sphere under the sky, 512x512.
nlohmann::json defaultSessionSceneJson();

}  // namespace brdfa::server
