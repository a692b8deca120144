#include "isolation/remote_renderer.h"

#include <pthread.h>
#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "core/worker_process.h"
#include "isolation/render_wire.h"
#include "programs/compile_protocol.h"

namespace brdfa {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;
namespace wire = render_wire;

constexpr uint32_t kMaxReplyBytes = 512u << 20;  // a 4096^2 frame with float pixels is 320 MiB
constexpr double kStartSeconds = 60.0;           // opening a device and warming compile workers
constexpr double kRestartRetrySeconds = 1.0;     // between failed starts of a replacement
// A worker that says nothing this long (it beats every second) is stuck whole: killed.
constexpr double kSilentSeconds = 10.0;

// Which budget a request's device work runs under (the worker applies it per build or
// submission; here it bounds a worker that no longer answers).
enum class Budget { Build, Pass, Check };

std::string secondsText(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%g s", s);
  return text;
}

std::string mibText(uint64_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }

struct Pending {
  uint64_t id = 0;
  uint64_t generation = 0;
  Budget budget = Budget::Pass;
  Clock::time_point start;
  std::vector<std::string> programs;  // program keys the request builds or runs
  std::vector<std::string> names;     // their BRDFs' names, for messages
  uint64_t view = 0;
  bool done = false;  // reply holds the worker's answer
  bool lost = false;  // the worker was replaced before it answered
  // Signalled (under the renderer's mutex) when done or lost turns true: only the one caller
  // wakes for its reply (a notify_all per reply woke every waiting session, the watchdog
  // included, and under a loaded CPU each wake-up costs a scheduling delay).
  std::condition_variable answered;
  std::optional<Error> blame;  // set when this request caused the replacement
  wire::Message reply;
  std::string op;         // for the channel counters
  size_t bytesSent = 0;   // the request's frame
  bool inFlight = false;  // written, and neither answered nor lost yet
};

struct Call {
  json head;
  Budget budget = Budget::Pass;
  std::vector<std::string> programs;
  std::vector<std::string> names;
  uint64_t view = 0;
};

// Waits up to `seconds` for one reply on `fd`, passing over events (a spare worker's heartbeats
// wait in its socket).
Result<wire::Message> receive(int fd, double seconds) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0 || ::poll(&p, 1, static_cast<int>(left)) <= 0)
      return makeError(ErrorCode::DeviceError, "the render worker did not answer within " + secondsText(seconds));
    std::string frame;
    wire::Message m;
    if (!compile_protocol::readFrame(fd, frame, kMaxReplyBytes) || !wire::decode(frame, m))
      return makeError(ErrorCode::DeviceError, "the render worker closed its channel");
    if (!m.head.contains("event")) return m;
  }
}

// One request and its reply on a channel nobody else reads yet (a worker being started).
Result<json> roundTrip(int fd, json head, double seconds) {
  if (!compile_protocol::writeFrame(fd, wire::encode(wire::Message{std::move(head), {}})))
    return makeError(ErrorCode::DeviceError, "the render worker closed its channel");
  auto m = receive(fd, seconds);
  if (!m) return m.takeError();
  if (!m->head.value("ok", false)) return wire::errorFromJson(m->head.value("error", json::object()));
  return m->head.value("value", json());
}

class RemoteRenderer;

// The programs of a scene's objects: keys for the quarantine and names for its messages.
struct ScenePrograms {
  std::vector<std::string> keys, names;
};

ScenePrograms programsOf(const Scene& scene) {
  ScenePrograms p;
  for (const SceneObject& o : scene.objects) {
    p.keys.push_back(wire::programKey(*o.brdf));
    p.names.push_back("'" + o.brdfName + "'");
  }
  return p;
}

class RemoteView : public RenderView {
 public:
  RemoteView(std::shared_ptr<RemoteRenderer> renderer, uint64_t id) : r_(std::move(renderer)), id_(id) {}
  ~RemoteView() override;
  Result<void> setScene(const Scene& scene) override;
  using RenderView::renderPass;
  Result<FrameStats> renderPass(double frameTargetMs) override;
  FrameStats stats() const override {
    std::lock_guard lock(mutex_);
    return stats_;
  }
  Result<Frame> readFrame(bool linear) override;
  void interruptPass() override;

 private:
  // Makes the view exist in the current worker, with its last scene (restored after a worker is replaced).
  Result<void> ensureRemote();
  Result<wire::Message> viewCall(json head, Budget budget, const ScenePrograms& programs);

  std::shared_ptr<RemoteRenderer> r_;
  const uint64_t id_;
  mutable std::mutex mutex_;
  uint64_t generation_ = 0;  // the worker generation the view exists in (0: none yet)
  std::optional<Scene> scene_;
  ScenePrograms programs_;       // of scene_ (hashing a program's code on every pass would cost)
  std::optional<Error> failed_;  // its pass overran: sticky until a new scene
  FrameStats stats_;
};

class RemoteRenderer : public Renderer, public std::enable_shared_from_this<RemoteRenderer> {
 public:
  explicit RemoteRenderer(const RendererOptions& options) : options_(options) {
    options_.spareProcesses = 1;  // keepSpare(): one idle worker, counted in the live one's budget
    // The worker derives its own limit from the budget (LocalRenderer::processMemoryLimit); the
    // one kept here only backs up a worker too stuck to report itself.
    if (options_.memoryBudgetBytes > 0) supervisorMemoryLimit_ = options_.memoryBudgetBytes + (uint64_t(1) << 30);
    if (options_.workerMemoryBytes > 0) supervisorMemoryLimit_ = options_.workerMemoryBytes + (uint64_t(1) << 30);
    if (!worker_process::kMemoryBudgetsApply) supervisorMemoryLimit_ = 0;
#ifdef BRDFA_RENDER_WORKER_PATH
    workerPath_ = worker_process::find("brdfa-render-worker", "BRDFA_RENDER_WORKER", BRDFA_RENDER_WORKER_PATH);
#else
    workerPath_ = worker_process::find("brdfa-render-worker", "BRDFA_RENDER_WORKER", nullptr);
#endif
  }

  ~RemoteRenderer() override {
    cancel();
    if (watchdog_.joinable()) watchdog_.join();
    if (spareMaker_.joinable()) spareMaker_.join();
    retire(worker_, reader_);
  }

  Result<void> start() {
    auto started = startWorker();
    if (!started) return started.takeError();
    std::lock_guard lock(mutex_);
    adopt(started.value());
    // Named for top, perf and the bench's CPU breakdown.
    watchdog_ = std::thread([this] {
      ::pthread_setname_np(::pthread_self(), "brdfa-watchdog");
      watch();
    });
    spareMaker_ = std::thread([this] {
      ::pthread_setname_np(::pthread_self(), "brdfa-spare");
      keepSpare();
    });
    return {};
  }

  // --- Renderer ---
  const DeviceInfo& device() const override { return device_; }

  Result<CompileInfo> compileBrdf(const BrdfDefinition& brdf) override {
    auto m = request(brdfCall("compileBrdf", brdf, Budget::Build));
    if (!m) return m.takeError();
    return wire::compileInfoFromJson(m->head.at("value"));
  }

  Result<std::unique_ptr<RenderView>> createView() override {
    std::lock_guard lock(mutex_);
    return std::unique_ptr<RenderView>(new RemoteView(shared_from_this(), nextViewId_++));
  }

  Result<BrdfCheckReport> checkBrdf(const BrdfDefinition& brdf) override {
    auto m = request(brdfCall("checkBrdf", brdf, Budget::Check));
    if (!m) return m.takeError();
    return wire::brdfReportFromJson(m->head.at("value"));
  }

  Result<SamplerCheckReport> checkSampler(const BrdfDefinition& brdf) override {
    auto m = request(brdfCall("checkSampler", brdf, Budget::Check));
    if (!m) return m.takeError();
    return wire::samplerReportFromJson(m->head.at("value"));
  }

  // Analyses run under the pass budget per submission (the worker's rule for ops not named
  // check*): they are interactive, and a BRDF that loops forever must not hold the queue.
  Result<std::vector<Vec3>> evaluateBrdf(const BrdfDefinition& brdf, const std::vector<ParamSetting>& settings,
                                         const std::vector<DirectionPair>& pairs) override {
    Call c = brdfCall("analysisValues", brdf, Budget::Pass);
    c.head["settings"] = settings;
    c.head["pairs"] = wire::toJson(pairs);
    auto m = request(std::move(c));
    if (!m) return m.takeError();
    return m->head.at("value").get<std::vector<Vec3>>();
  }

  Result<std::vector<AlbedoEstimate>> estimateAlbedo(const BrdfDefinition& brdf,
                                                     const std::vector<ParamSetting>& settings,
                                                     const std::vector<Vec3>& views, uint32_t samplesPerView) override {
    Call c = brdfCall("analysisAlbedo", brdf, Budget::Pass);
    c.head["settings"] = settings;
    c.head["views"] = views;
    c.head["samples"] = samplesPerView;
    auto m = request(std::move(c));
    if (!m) return m.takeError();
    return wire::albedoFromJson(m->head.at("value"));
  }

  Result<EnvironmentSamplerReport> checkEnvironmentSampler(const std::string& environment) override {
    Call c;
    c.head = json{{"op", "checkEnvironmentSampler"}, {"environment", environment}};
    c.budget = Budget::Check;
    auto m = request(std::move(c));
    if (!m) return m.takeError();
    return wire::environmentReportFromJson(m->head.at("value"));
  }

  Result<int> preloadFromCache(const BrdfDefinition& brdf) override {
    auto m = request(brdfCall("preload", brdf, Budget::Check));
    if (!m) return m.takeError();
    return m->head.at("value").get<int>();
  }

  RendererCounters counters() const override {
    Call c;
    c.head = json{{"op", "counters"}};
    bool live;
    uint64_t generationAsked;
    {
      std::lock_guard lock(mutex_);
      live = alive_;
      generationAsked = generation_;
    }
    // Health checks must answer while a replacement starts: then only the figures kept here.
    auto m = live ? const_cast<RemoteRenderer*>(this)->request(std::move(c))
                  : Result<wire::Message>(makeError(ErrorCode::DeviceError, "restarting"));
    RendererCounters worker;
    if (m) worker = wire::countersFromJson(m->head.at("value"));
    std::lock_guard lock(mutex_);
    // A reply from a worker replaced meanwhile is already in retiredCounters_.
    if (m && generation_ == generationAsked) lastWorkerCounters_ = worker;
    RendererCounters out = worker;
    out.addCumulative(retiredCounters_);
    out.workerRestarts = restarts_;
    out.quarantinedPrograms = quarantine_.size();
    out.channel = channel_;
    out.channelInFlightSeconds =
        inFlightSeconds_ + double(inFlight_) * std::chrono::duration<double>(Clock::now() - inFlightSince_).count();
    out.channelMaxInFlight = maxInFlight_;
    if (!m) out.memory.budget = options_.memoryBudgetBytes;
    return out;
  }

  Result<void> registerAsset(const std::string& name, AssetKind kind, const std::string& path) override {
    Call c;
    c.head = json{{"op", "registerAsset"}, {"name", name}, {"kind", kind}, {"path", path}};
    auto m = request(std::move(c));
    if (!m) return m.takeError();
    // Kept to register again in a replacement worker.
    std::lock_guard lock(mutex_);
    assets_[{name, kind}] = path;
    return {};
  }

  std::vector<std::string> environmentNames() const override { return names("environments"); }
  std::vector<std::string> meshNames() const override { return names("meshes"); }
  std::vector<std::string> textureNames() const override { return names("textures"); }

  void cancel() override {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
    spareWanted_.notify_all();
    // Whatever the worker is doing, nobody waits for it now (the destructor reaps it).
    if (worker_.pid > 0) ::kill(worker_.pid, SIGKILL);
    alive_ = false;
    loseAllPending();
    changed_.notify_all();
  }

  // --- for RemoteView ---
  uint64_t generation() const {
    std::lock_guard lock(mutex_);
    return generation_;
  }

  // The error a view's overrunning pass left for it, once.
  std::optional<Error> takeViewFailure(uint64_t view) {
    std::lock_guard lock(mutex_);
    auto it = failedViews_.find(view);
    if (it == failedViews_.end()) return std::nullopt;
    Error e = std::move(it->second);
    failedViews_.erase(it);
    return e;
  }

  // Every one of `programs` built within budget before (the worker has them, barring a restart).
  bool allBuilt(const std::vector<std::string>& programs) {
    std::lock_guard lock(mutex_);
    return std::all_of(programs.begin(), programs.end(), [&](const std::string& p) { return built_.count(p) > 0; });
  }

  // Programs that built (setScene) or ran a pass within budget: not blamed for a later overrun
  // of that kind.
  void noteProven(Budget budget, const std::vector<std::string>& programs) {
    std::lock_guard lock(mutex_);
    auto& proven = budget == Budget::Build ? built_ : rendered_;
    proven.insert(programs.begin(), programs.end());
  }

  // Sends `c` and waits for its reply, again to a replacement worker when the one it went to is
  // killed for another request's sake (after `prepare`, which restores what the request needs).
  Result<wire::Message> request(Call c, const std::function<Result<void>()>& prepare = {}) {
    for (int attempt = 0; attempt < 3; ++attempt) {
      if (prepare)
        if (Result<void> ready = prepare(); !ready) return ready.takeError();
      std::shared_ptr<Pending> p;
      if (Result<void> sent = send(c, p); !sent) return sent.takeError();
      std::unique_lock lock(mutex_);
      p->answered.wait(lock, [&] { return p->done || p->lost; });
      pending_.erase(p->id);
      if (p->blame) return *p->blame;
      if (stopping_) return makeError(ErrorCode::DeviceError, "the renderer is shutting down");
      if (!p->done) {
        // Lost with a worker killed for another request's sake (or found dead): again, once
        // the watchdog has replaced it.
        changed_.wait(lock, [&] { return stopping_ || generation_ != p->generation; });
        continue;
      }
      if (!p->reply.head.value("ok", false)) return wire::errorFromJson(p->reply.head.value("error", json::object()));
      return std::move(p->reply);
    }
    return makeError(ErrorCode::DeviceError, "the render worker was replaced three times during this request");
  }

 private:
  Call brdfCall(const char* op, const BrdfDefinition& brdf, Budget budget) {
    Call c;
    c.head = json{{"op", op}, {"brdf", wire::toJson(brdf)}};
    c.budget = budget;
    c.programs = {wire::programKey(brdf)};
    c.names = {"the validated BRDF"};
    return c;
  }

  std::vector<std::string> names(const char* kind) const {
    Call c;
    c.head = json{{"op", "names"}};
    auto m = const_cast<RemoteRenderer*>(this)->request(std::move(c));
    if (!m) return {};
    return m->head.at("value").at(kind).get<std::vector<std::string>>();
  }

  // Every request in flight is answered "lost" (mutex_ held): its caller tries again, or stops.
  void loseAllPending() {
    for (auto& [id, p] : pending_) {
      setInFlightLocked(*p, false);
      p->lost = true;
      p->answered.notify_one();
    }
  }

  // Registers `c` as pending and writes it to the live worker (waiting for one while a
  // replacement starts). Fails at once when it uses a quarantined program.
  Result<void> send(Call& c, std::shared_ptr<Pending>& out) {
    std::unique_lock lock(mutex_);
    for (const std::string& key : c.programs)
      if (auto q = quarantine_.find(key); q != quarantine_.end()) return q->second;
    const auto deadline = Clock::now() + std::chrono::duration<double>(kStartSeconds);
    while (!alive_ && !stopping_)
      if (changed_.wait_until(lock, deadline) == std::cv_status::timeout && !alive_)
        return makeError(ErrorCode::DeviceError, "the render worker is not available" +
                                                     (startError_.empty() ? std::string() : ": " + startError_));
    if (stopping_) return makeError(ErrorCode::DeviceError, "the renderer is shutting down");
    auto p = std::make_shared<Pending>();
    p->id = nextId_++;
    p->generation = generation_;
    p->budget = c.budget;
    p->start = Clock::now();
    p->programs = c.programs;
    p->names = c.names;
    p->view = c.view;
    c.head["id"] = p->id;
    p->op = c.head.value("op", std::string());
    pending_[p->id] = p;
    // Written under the lock: a replacement cannot close the socket meanwhile. The worker reads
    // requests on a thread of its own, so this never waits for device work.
    const std::string frame = wire::encode(wire::Message{c.head, {}});
    p->bytesSent = frame.size() + 4;  // with the frame's length prefix
    if (!compile_protocol::writeFrame(worker_.fd, frame)) {
      // The worker is gone; the watchdog sees its channel close and replaces it.
      p->lost = true;
    } else {
      setInFlightLocked(*p, true);
    }
    out = p;
    return {};
  }

  // Counts `p` into or out of the requests in flight (mutex_ held).
  void setInFlightLocked(Pending& p, bool inFlight) {
    if (p.inFlight == inFlight) return;
    const Clock::time_point now = Clock::now();
    inFlightSeconds_ += double(inFlight_) * std::chrono::duration<double>(now - inFlightSince_).count();
    inFlightSince_ = now;
    p.inFlight = inFlight;
    inFlight ? ++inFlight_ : --inFlight_;
    maxInFlight_ = std::max(maxInFlight_, inFlight_);
  }

  // The channel counters of `p`, answered by `reply` of `replyBytes` (mutex_ held).
  void countReplyLocked(Pending& p, const wire::Message& reply, size_t replyBytes) {
    setInFlightLocked(p, false);
    RendererCounters::ChannelOp& op = channel_[p.op];
    op.requests += 1;
    op.bytesToWorker += p.bytesSent;
    op.bytesFromWorker += replyBytes;
    op.roundTripSeconds += std::chrono::duration<double>(Clock::now() - p.start).count();
    auto worker = reply.head.find("worker_us");
    if (worker != reply.head.end() && worker->is_array() && worker->size() == 2) {
      op.workerQueueSeconds += (*worker)[0].get<double>() / 1e6;
      op.workerServeSeconds += (*worker)[1].get<double>() / 1e6;
    }
  }

  // A worker with its device open (not yet live).
  Result<worker_process::Child> spawnWorker() {
    auto child = worker_process::spawn(workerPath_, {});
    if (!child) return child.takeError();
    worker_process::Child c = child.value();
    auto hello = roundTrip(c.fd, json{{"op", "start"}, {"options", wire::toJson(options_)}}, kStartSeconds);
    if (!hello) {
      worker_process::killAndReap(c);
      return hello.takeError();
    }
    std::lock_guard lock(mutex_);
    device_ = wire::deviceFromJson(hello.value());
    return c;
  }

  // A worker ready to go live: the spare when there is one (started beforehand, so a
  // replacement costs no device start), else a new one; with the registered assets.
  Result<worker_process::Child> startWorker() {
    std::optional<worker_process::Child> spare;
    {
      std::lock_guard lock(mutex_);
      spare.swap(spare_);
      spareWanted_.notify_all();
    }
    Result<worker_process::Child> started = spare ? Result<worker_process::Child>(*spare) : spawnWorker();
    if (!started) return started;
    const worker_process::Child c = started.value();
    std::map<std::pair<std::string, AssetKind>, std::string> assets;
    {
      std::lock_guard lock(mutex_);
      assets = assets_;
    }
    for (const auto& [key, path] : assets) {
      auto done = roundTrip(
          c.fd, json{{"op", "registerAsset"}, {"id", 0}, {"name", key.first}, {"kind", key.second}, {"path", path}},
          kStartSeconds);
      if (!done)
        std::fprintf(stderr, "render worker: asset %s not registered again: %s\n", key.first.c_str(),
                     done.error().message.c_str());
    }
    return c;
  }

  // Ends a worker and its reader thread (mutex_ not held: the reader takes it). The socket is
  // closed only after the reader is done with it, so its number cannot be reused under it.
  static int retire(worker_process::Child& child, std::thread& reader) {
    if (child.fd >= 0) ::shutdown(child.fd, SHUT_RDWR);
    worker_process::Child process{child.pid, -1};
    const int status = worker_process::killAndReap(process);
    if (reader.joinable()) reader.join();
    if (child.fd >= 0) ::close(child.fd);
    child = {};
    return status;
  }

  // Makes `child` the live worker (mutex_ held).
  void adopt(worker_process::Child child) {
    worker_ = child;
    lastHeard_ = Clock::now();
    ++generation_;
    alive_ = true;
    startError_.clear();
    reader_ = std::thread([this, fd = child.fd, gen = generation_] {
      ::pthread_setname_np(::pthread_self(), "brdfa-channel");
      read(fd, gen);
    });
    changed_.notify_all();
  }

  void read(int fd, uint64_t generation) {
    for (;;) {
      std::string frame;
      wire::Message m;
      if (!compile_protocol::readFrame(fd, frame, kMaxReplyBytes) || !wire::decode(frame, m)) break;
      std::lock_guard lock(mutex_);
      if (generation != generation_) break;
      lastHeard_ = Clock::now();
      if (m.head.contains("event")) {
        if (m.head.at("event") == "overrun" && !overrun_) overrun_ = m.head;
        changed_.notify_all();
        continue;
      }
      auto it = pending_.find(m.head.value("id", uint64_t(0)));
      if (it == pending_.end() || it->second->generation != generation) continue;
      countReplyLocked(*it->second, m, frame.size() + 4);
      it->second->reply = std::move(m);
      it->second->done = true;
      it->second->answered.notify_one();
    }
    std::lock_guard lock(mutex_);
    if (generation == generation_) exited_ = true;
    changed_.notify_all();
  }

  // Keeps one spare worker started while the renderer runs.
  void keepSpare() {
    std::unique_lock lock(mutex_);
    while (!stopping_) {
      spareWanted_.wait(lock, [&] { return stopping_ || !spare_; });
      if (stopping_) break;
      lock.unlock();
      auto started = spawnWorker();
      lock.lock();
      if (started && !stopping_)
        spare_ = started.value();
      else if (started)
        worker_process::killAndReap(started.value());
      else  // guard: a failing start must not spin
        spareWanted_.wait_for(lock, std::chrono::duration<double>(kRestartRetrySeconds), [&] { return stopping_; });
    }
    if (spare_) worker_process::killAndReap(*spare_);
    spare_.reset();
  }

  std::shared_ptr<Pending> oldestPending() const {
    std::shared_ptr<Pending> oldest;
    for (const auto& [id, p] : pending_)
      if (!p->done && !p->lost && (!oldest || p->start < oldest->start)) oldest = p;
    return oldest;
  }

  void watch() {
    std::unique_lock lock(mutex_);
    while (!stopping_) {
      changed_.wait_for(lock, std::chrono::milliseconds(100), [&] { return stopping_ || exited_ || overrun_; });
      if (stopping_) break;
      if (!alive_) {  // a replacement failed to start: try again
        lock.unlock();
        std::this_thread::sleep_for(std::chrono::duration<double>(kRestartRetrySeconds));
        goLive(lock);
        continue;
      }
      std::shared_ptr<Pending> culprit;
      std::string kind, resource;
      bool replace = false;
      if (overrun_) {
        auto it = pending_.find(overrun_->value("id", uint64_t(0)));
        if (it != pending_.end()) culprit = it->second;
        kind = overrun_->value("kind", std::string("pass"));
        resource = overrun_->value("resource", std::string("time"));
        if (resource == "memory") memoryLimit_ = overrun_->value("limit", supervisorMemoryLimit_);
        replace = true;
      } else if (exited_) {
        replace = true;
      } else if (std::chrono::duration<double>(Clock::now() - lastHeard_).count() > kSilentSeconds) {
        culprit = oldestPending();
        kind = culprit && culprit->budget == Budget::Build ? "build" : "pass";
        resource = "time";
        replace = true;
      } else if (supervisorMemoryLimit_ > 0 && worker_process::residentBytes(worker_.pid) > supervisorMemoryLimit_) {
        // Past the worker's own watch (it reads its size every 50 ms): it is not looking.
        culprit = oldestPending();
        kind = "build";
        resource = "memory";
        memoryLimit_ = supervisorMemoryLimit_;
        replace = true;
      }
      if (replace) replace_(lock, culprit, kind, resource);
    }
  }

  Error blameError(const Pending& p, const std::string& kind, const std::string& resource,
                   const std::vector<std::string>& quarantined) const {
    const bool build = kind == "build";
    std::string budget = resource == "memory"        ? "the render worker's memory budget of " + mibText(memoryLimit_)
                         : p.budget == Budget::Check ? "the check budget of " + secondsText(options_.checkSeconds)
                         : build ? "the pipeline build budget of " + secondsText(options_.buildSeconds)
                                 : "the budget of " + secondsText(options_.passSeconds) + " per submission";
    std::string what = build                       ? "building its pipeline"
                       : p.budget == Budget::Check ? "its check"
                                                   : "a pass of its scene";
    std::string names;
    for (size_t i = 0; i < p.programs.size(); ++i) {
      if (std::find(quarantined.begin(), quarantined.end(), p.programs[i]) == quarantined.end()) continue;
      names += (names.empty() ? "" : ", ") + std::string(i < p.names.size() ? p.names[i] : "?");
    }
    Error e;
    e.code = ErrorCode::RenderBudget;
    if (!names.empty())
      e.message = "BRDF " + names + " is quarantined: " + what + " went past " + budget +
                  ", so the render worker was restarted (other sessions go on); change its code to try again";
    else
      e.message = "this scene went past " + budget + " (" + what +
                  "), so the render worker was restarted; use a smaller image or fewer samples per frame";
    e.diagnostics.push_back(Diagnostic{0, 0, "error", e.message});
    return e;
  }

  // Kills the worker, blames `culprit` (when known), and starts a replacement (mutex_ held on
  // entry and exit; released while the old worker is reaped and the new one starts).
  void replace_(std::unique_lock<std::mutex>& lock, std::shared_ptr<Pending> culprit, const std::string& kind,
                const std::string& resource) {
    alive_ = false;
    worker_process::Child dead = worker_;
    worker_ = {};
    std::thread reader = std::move(reader_);
    const bool overran = overrun_.has_value();
    overrun_.reset();
    exited_ = false;
    ++generation_;  // replies still arriving from the old worker are dropped
    ++restarts_;
    // Its compiles and cache hits as last read; those since that read are not counted.
    retiredCounters_.addCumulative(lastWorkerCounters_);
    lastWorkerCounters_ = {};
    std::string blamed = "none";
    if (culprit) {
      // Programs proven within budget by earlier work of this kind are not the cause.
      const auto& proven = kind == "build" && culprit->budget != Budget::Check ? built_ : rendered_;
      std::vector<std::string> quarantined;
      for (const std::string& key : culprit->programs)
        if (!proven.count(key) || culprit->budget == Budget::Check) quarantined.push_back(key);
      Error e = blameError(*culprit, kind, resource, quarantined);
      for (const std::string& key : quarantined) quarantine_[key] = e;
      culprit->blame = e;
      // A view whose pass overran is not restored with that scene.
      if (culprit->view && kind == "pass") failedViews_[culprit->view] = e;
      blamed = e.message;
    }
    loseAllPending();
    changed_.notify_all();
    lock.unlock();
    const int status = retire(dead, reader);
    std::fprintf(stderr, "render worker %s; restarting. Blamed: %s\n",
                 overran   ? "overran its budget"
                 : culprit ? "fell silent"
                           : ("ended (" + worker_process::describeStatus(status) + ")").c_str(),
                 blamed.c_str());
    goLive(lock);
  }

  // Starts a worker (mutex_ not held on entry, held on exit) and makes it live, unless the
  // renderer is stopping; a failed start is kept for callers to see and retried by watch().
  void goLive(std::unique_lock<std::mutex>& lock) {
    auto started = startWorker();
    lock.lock();
    if (stopping_) {
      if (started) worker_process::killAndReap(started.value());
      return;
    }
    if (started)
      adopt(started.value());
    else
      startError_ = started.error().message;
  }

  RendererOptions options_;
  uint64_t supervisorMemoryLimit_ = 0;  // the worker's resident memory past which it is replaced from here
  uint64_t memoryLimit_ = 0;            // the limit the last memory overrun passed (for its message)
  std::string workerPath_;
  DeviceInfo device_;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  worker_process::Child worker_;
  uint64_t generation_ = 0;
  bool alive_ = false;
  bool exited_ = false;
  bool stopping_ = false;
  std::optional<json> overrun_;
  Clock::time_point lastHeard_;  // the live worker's last message
  std::string startError_;
  std::thread reader_, watchdog_, spareMaker_;
  std::optional<worker_process::Child> spare_;
  std::condition_variable_any spareWanted_;
  std::map<uint64_t, std::shared_ptr<Pending>> pending_;
  // The channel's figures (RendererCounters::channel), across workers.
  std::map<std::string, RendererCounters::ChannelOp> channel_;
  uint64_t inFlight_ = 0, maxInFlight_ = 0;
  double inFlightSeconds_ = 0;  // up to inFlightSince_
  Clock::time_point inFlightSince_ = Clock::now();
  uint64_t nextId_ = 1;
  uint64_t nextViewId_ = 1;
  uint64_t restarts_ = 0;
  // The cumulative counters of replaced workers, and the current worker's latest reading.
  RendererCounters retiredCounters_;
  mutable RendererCounters lastWorkerCounters_;
  std::map<std::string, Error> quarantine_;
  std::set<std::string> built_, rendered_;
  std::map<uint64_t, Error> failedViews_;
  std::map<std::pair<std::string, AssetKind>, std::string> assets_;
};

RemoteView::~RemoteView() {
  std::lock_guard lock(mutex_);
  // Waited for: the view's memory is back in the budget when its owner goes on (a session
  // deleted, a refused one-shot). Nothing to do when the worker it lived in is gone.
  if (generation_ && generation_ == r_->generation()) {
    Call c;
    c.head = json{{"op", "destroyView"}, {"view", id_}};
    (void)r_->request(std::move(c));
  }
}

Result<void> RemoteView::ensureRemote() {
  const uint64_t generation = r_->generation();
  if (generation == generation_) return {};
  if (auto failure = r_->takeViewFailure(id_)) {
    failed_ = std::move(failure);
    scene_.reset();
    programs_ = {};
  }
  Call create;
  create.head = json{{"op", "createView"}, {"view", id_}};
  auto created = r_->request(std::move(create));
  if (!created) return created.takeError();
  if (scene_) {
    Call restore;
    restore.head = json{{"op", "setScene"}, {"view", id_}, {"scene", wire::toJson(*scene_)}};
    restore.budget = Budget::Build;
    restore.view = id_;
    restore.programs = programs_.keys;
    restore.names = programs_.names;
    auto restored = r_->request(std::move(restore));
    if (!restored) {
      // Its scene uses a program quarantined meanwhile (or cannot be built again): the view
      // keeps the error until it gets a new scene.
      failed_ = restored.takeError();
      scene_.reset();
      programs_ = {};
    }
  }
  generation_ = generation;
  return {};
}

Result<wire::Message> RemoteView::viewCall(json head, Budget budget, const ScenePrograms& programs) {
  Call c;
  c.head = std::move(head);
  c.head["view"] = id_;
  c.budget = budget;
  c.view = id_;
  c.programs = programs.keys;
  c.names = programs.names;
  return r_->request(std::move(c), [this] { return ensureRemote(); });
}

Result<void> RemoteView::setScene(const Scene& scene) {
  for (const SceneObject& o : scene.objects)
    if (!o.brdf) return makeError(ErrorCode::InvalidArgument, "an object has no BRDF");
  ScenePrograms programs = programsOf(scene);
  if (!r_->allBuilt(programs.keys)) {
    // A BRDF new to the worker: it builds the programs before the view's lock, which a pass in
    // flight holds, meanwhile (RenderView::prepareScene), under the build budget, and the
    // setScene below finds them. A view not in the current worker ignores it. (A camera move
    // or a slider skips the round trip: its programs are built.)
    Call c;
    c.head = json{{"op", "prepareScene"}, {"view", id_}, {"scene", wire::toJson(scene)}};
    c.budget = Budget::Build;
    c.view = id_;
    c.programs = programs.keys;
    c.names = programs.names;
    (void)r_->request(std::move(c));
  }
  std::lock_guard lock(mutex_);
  auto m = viewCall(json{{"op", "setScene"}, {"scene", wire::toJson(scene)}}, Budget::Build, programs);
  if (!m) return m.takeError();
  scene_ = scene;
  programs_ = std::move(programs);
  failed_.reset();
  stats_ = wire::statsFromJson(m->head.at("value"));
  r_->noteProven(Budget::Build, programs_.keys);
  return {};
}

Result<FrameStats> RemoteView::renderPass(double frameTargetMs) {
  std::lock_guard lock(mutex_);
  if (Result<void> ready = ensureRemote(); !ready) return ready.takeError();
  if (failed_) return *failed_;
  auto m = viewCall(json{{"op", "renderPass"}, {"frame_target_ms", frameTargetMs}}, Budget::Pass, programs_);
  if (!m) {
    if (m.error().code == ErrorCode::RenderBudget) failed_ = m.error();
    return m.takeError();
  }
  stats_ = wire::statsFromJson(m->head.at("value"));
  r_->noteProven(Budget::Pass, programs_.keys);
  return stats_;
}

void RemoteView::interruptPass() {
  // Not under mutex_, which the pass to interrupt holds; the worker serves it on another
  // thread. A view not in the current worker (being restored) has no pass to interrupt.
  Call c;
  c.head = json{{"op", "interruptPass"}, {"view", id_}};
  (void)r_->request(std::move(c));
}

Result<Frame> RemoteView::readFrame(bool linear) {
  std::lock_guard lock(mutex_);
  if (Result<void> ready = ensureRemote(); !ready) return ready.takeError();
  if (failed_) return *failed_;
  auto m = viewCall(json{{"op", "readFrame"}, {"linear", linear}}, Budget::Pass, {});
  if (!m) return m.takeError();
  const json& v = m->head.at("value");
  Frame f;
  f.width = v.at("width").get<int>();
  f.height = v.at("height").get<int>();
  f.stats = wire::statsFromJson(v.at("stats"));
  const size_t pixels = size_t(f.width) * size_t(f.height);
  const std::string& tail = m->tail;
  const bool floats = v.at("linear").get<bool>();
  if (tail.size() != pixels * 4 + (floats ? pixels * 16 : 0))
    return makeError(ErrorCode::Internal, "the render worker sent a frame of the wrong size");
  f.rgba8.assign(tail.begin(), tail.begin() + pixels * 4);
  if (floats) {
    f.rgba32f.resize(pixels * 4);
    std::memcpy(f.rgba32f.data(), tail.data() + pixels * 4, pixels * 16);
  }
  stats_ = f.stats;
  return f;
}

}  // namespace

Result<std::shared_ptr<Renderer>> createRemoteRenderer(const RendererOptions& options) {
  auto r = std::make_shared<RemoteRenderer>(options);
  if (Result<void> started = r->start(); !started) return started.takeError();
  return std::shared_ptr<Renderer>(std::move(r));
}

}  // namespace brdfa
