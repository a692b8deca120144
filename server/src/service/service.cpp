#include "service/service.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include <unistd.h>

#include "http/request_body.h"

namespace brdfa::server {

bool OwnerCounter::take(const std::string& owner, int limit, int& held) {
  std::lock_guard lock(mutex_);
  int& n = held_[owner];
  held = n;
  if (limit > 0 && n >= limit) {
    if (n == 0) held_.erase(owner);
    return false;
  }
  ++n;
  return true;
}

void OwnerCounter::release(const std::string& owner) {
  std::lock_guard lock(mutex_);
  if (auto it = held_.find(owner); it != held_.end() && --it->second <= 0) held_.erase(it);
}

nlohmann::json defaultSessionSceneJson() {
  return {{"environment", {{"name", "sky"}, {"visible", true}}},
          {"objects", nlohmann::json::array({{{"mesh", "sphere"}, {"brdf", "ggx"}}})},
          {"render", {{"width", 512}, {"height", 512}, {"samples_per_frame", 4}, {"max_samples", 4096}}}};
}

namespace {

// Applies `json` to the session; returns the error message on failure.
std::optional<std::string> tryApply(Service& service, Session& session, std::unique_lock<std::mutex>& lock,
                                    const nlohmann::json& json) {
  Result<Scene> scene = sceneFromJson(json, service.resolver(localIdentity()));
  if (!scene) return scene.error().message;
  Result<void> applied = session.applyScene(lock, scene.value(), sceneToJson(scene.value()));
  if (!applied) return applied.error().message;
  return std::nullopt;
}

}  // namespace

Result<std::unique_ptr<Service>> Service::create(const ServerConfig& config, std::vector<std::string>& log) {
  auto service = std::make_unique<Service>();
  service->config = config;
  service->maxStreams = std::max(1, std::min(kMaxStreams, config.threads * 3 / 4));
  service->maxFrameWaiters = std::max(1, config.threads / 4);
  service->renderSlots.recordWaitsIn(&service->metrics.renderQueueWait);
  service->uploadSlots.recordWaitsIn(&service->metrics.uploadQueueWait);

  std::error_code ec;
  std::filesystem::create_directories(config.dataDir, ec);
  if (ec) log.push_back("warning: cannot create data directory " + config.dataDir + ": " + ec.message());
  BRDFA_TRY_ASSIGN(std::unique_ptr<Authenticator> auth, Authenticator::create(config, log));
  service->auth = std::move(auth);

  RendererOptions options;
  options.deviceName = config.deviceName;
  options.shaderDir = (std::filesystem::path(config.root) / "shaders").string();
  // Both caches live in the data dir: SPIR-V by content hash, and Mesa's own shader cache.
  options.cacheDir = (std::filesystem::path(config.dataDir) / "cache" / "spirv").string();
  options.driverCacheDir = (std::filesystem::path(config.dataDir) / "cache" / "mesa").string();
  options.loadCache = config.loadCache;
  options.compileSeconds = config.compileTimeoutSec;
  // Half the machine's RAM unless told: the rest is for the driver, uploads, caches and the OS.
  const uint64_t ram = uint64_t(sysconf(_SC_PHYS_PAGES)) * uint64_t(sysconf(_SC_PAGESIZE));
  // One budget, two holders: upload bodies in flight here (an eighth), everything the renderer
  // holds there (the rest; MemoryUsage lists it).
  const uint64_t budget = config.maxMemoryMiB ? config.maxMemoryMiB << 20 : ram / 2;
  const uint64_t uploadShare = budget / 8;
  service->memoryBudgetBytes = budget;
  service->uploadMemory = std::make_unique<RenderSlots>(uploadShare, kMaxQueuedUploadChecks);
  options.memoryBudgetBytes = budget - uploadShare;
  // A compile's memory is part of the budget: a sixteenth of it, unless told (the floor leaves
  // glslang room for Disney's BRDF with the integrator).
  options.compileMemoryMiB = config.compileMemoryMiB > 0 ? size_t(config.compileMemoryMiB)
                                                         : size_t(std::clamp<uint64_t>(budget >> 24, 64, 1024));
  options.memoryBudgetLabel = "the server's memory budget (--max-memory " + std::to_string(budget >> 20) + " MiB, " +
                              std::to_string(options.memoryBudgetBytes >> 20) + " MiB of it for the renderer)";
  options.isolate = !config.inProcess;
  options.buildSeconds = config.buildBudgetSec;
  options.passSeconds = config.passBudgetSec;
  options.checkSeconds = config.checkBudgetSec;
  BRDFA_TRY_ASSIGN(std::shared_ptr<Renderer> renderer, Renderer::create(options));
  service->renderer = std::move(renderer);

  AssetStoreLimits assetLimits;
  assetLimits.file.maxBytes = config.maxUploadBytes;
  assetLimits.file.maxTriangles = config.maxUploadTriangles;
  assetLimits.file.maxPixels = config.maxUploadPixels;
  assetLimits.maxAssets = static_cast<size_t>(config.maxAssets);
  assetLimits.maxTotalBytes = config.maxAssetsBytes;
  service->assets = std::make_unique<AssetStore>(service->renderer, config.dataDir, assetLimits, service->uploadSlots);
  for (std::string& msg : service->assets->load(config.environmentDirs)) log.push_back(std::move(msg));

  for (std::string& msg :
       service->brdfs.load((std::filesystem::path(config.root) / "shaders" / "brdfs").string(), config.dataDir))
    log.push_back(std::move(msg));
  service->jobs = std::make_unique<JobManager>(service->renderer, kJobWorkers, service->idPrefix());
  if (config.hotLoad) service->hotLoader.start(service->renderer, service->brdfs.list());

  service->sessions = std::make_unique<SessionManager>(
      service->renderer, std::chrono::milliseconds(std::chrono::seconds(config.idleTimeoutSec)),
      static_cast<size_t>(config.maxSessions),
      std::chrono::milliseconds(std::chrono::seconds(config.sessionReclaimSec)), service->idPrefix(),
      &service->metrics);
  if (!config.replica.empty()) {
    SessionManager* sessions = service->sessions.get();
    service->directory =
        std::make_unique<SessionDirectory>(config.dataDir, config.replica, [sessions] { return sessions->list(); });
    SessionDirectory* directory = service->directory.get();
    sessions->onChange([directory] { directory->publish(); });
    directory->start();
  }
  SessionManager::Created created = service->sessions->create(kDefaultSessionId);
  if (!created.session) {
    return makeError(created.error ? created.error->code : ErrorCode::Internal,
                     "cannot create the default session: " + (created.error ? created.error->message : "session cap"));
  }
  // Deferred so start-up compiles nothing. If the sky or GGX is missing (a stripped-down
  // install), fall back to the all-defaults scene rather than leaving `default` empty.
  Service* raw = service.get();
  created.session->setInitializer([raw](Session& session, std::unique_lock<std::mutex>& lock) {
    auto err = tryApply(*raw, session, lock, defaultSessionSceneJson());
    if (!err) return;
    std::fprintf(stderr, "warning: default scene not applied (%s); using the built-in defaults\n", err->c_str());
    if (auto err2 = tryApply(*raw, session, lock, nlohmann::json::object()))
      std::fprintf(stderr, "warning: default session has no scene: %s\n", err2->c_str());
  });
  return service;
}

SceneResolver Service::resolver(const Identity& who, std::shared_ptr<const BrdfDefinition> inlineBrdf) {
  // Another replica's uploads since the last look become names a scene may use.
  if (assets) assets->refreshFromDisk();
  SceneResolver r;
  // Someone else's BRDF resolves exactly like one that does not exist.
  r.findBrdf = [this, who](std::string_view name) { return readableBrdf(who, name); };
  r.inlineBrdf = std::move(inlineBrdf);
  auto visible = [&](std::vector<std::string> names) {
    if (assets)
      std::erase_if(names, [&](const std::string& n) { return !assets->visible(n, who.user, who.teacher()); });
    return names;
  };
  r.environments = visible(renderer->environmentNames());
  r.meshes = visible(renderer->meshNames());
  r.textures = visible(renderer->textureNames());
  return r;
}

std::shared_ptr<const BrdfEntry> Service::readableBrdf(const Identity& who, std::string_view name) {
  if (auto entry = brdfs.find(name)) return canReadBrdf(who, *entry) ? entry : nullptr;
  if (!assets || !assets->visible(name, who.user, who.teacher())) return nullptr;
  return assets->measuredBrdf(name);
}

size_t Service::maxRequestBody() const {
  return std::max<size_t>(kMaxJsonBody, static_cast<size_t>(config.maxUploadBytes) + kMultipartOverhead);
}

void Service::beginShutdown() {
  stopping = true;
  // Device work in flight (a pass, a build) is abandoned, not waited for: exit within seconds.
  // First, as what follows joins threads that may be waiting for the device.
  if (renderer) renderer->cancel();
  if (jobs) jobs->stop();
  hotLoader.stop();
  renderSlots.shutdown();
  uploadSlots.shutdown();
  if (uploadMemory) uploadMemory->shutdown();
  if (directory) directory->stop();  // this replica's sessions leave the class-wide list
  if (sessions) sessions->stopAll();
}

}  // namespace brdfa::server
