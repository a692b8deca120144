// brdfa-render-worker: owns the Vulkan device for a RemoteRenderer (remote_renderer.h), so a
// watchdog in the server can stop a pipeline build or a pass by killing this process. Reads
// request messages on stdin and writes replies on stdout (render_wire.h); each request runs on
// a thread of its own, as the renderer's API is thread-safe, so a long pass of one view never
// holds another's request. Exits at end of input (the server went away).
#include <pthread.h>
#include <sys/prctl.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <cstdio>
#include <map>
#include <set>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "brdfa/heap_tuning.h"
#include "brdfa/renderer.h"

#include "core/worker_process.h"
#include "device/device_activity.h"
#include "isolation/render_wire.h"
#include "programs/compile_protocol.h"
#include "render/local_renderer.h"

namespace brdfa {
namespace {

using nlohmann::json;
namespace wire = render_wire;

constexpr uint32_t kMaxRequestBytes = 64u << 20;  // a scene with 64 objects' sources, far below
// On a CPU device, work past this many times its budget in wall time is stopped even without
// the CPU time to show for it (watch()).
constexpr double kStuckFactor = 3.0;

class Worker {
 public:
  Worker(int channel, std::shared_ptr<Renderer> renderer) : channel_(channel), renderer_(std::move(renderer)) {}

  void serve(const RendererOptions& options) {
    std::thread([this, options] {
      ::pthread_setname_np(::pthread_self(), "worker-watch");
      watch(options);
    }).detach();
    for (;;) {
      std::string frame;
      if (!compile_protocol::readFrame(channel_, frame, kMaxRequestBytes)) return;
      wire::Message request;
      if (!wire::decode(frame, request)) return;
      dispatch(std::move(request));
    }
  }

 private:
  // Requests run on threads of their own (a pass may wait on the device while the next request
  // is a scene change), taken from a pool: a new thread starts behind every running one on a
  // loaded CPU (the scheduler's start debit), a waiting one is woken ahead: under busy loops, a
  // thread per request made a slider change's frame slower.
  void dispatch(wire::Message request) {
    std::lock_guard lock(poolMutex_);
    queue_.push_back(Queued{std::move(request), std::chrono::steady_clock::now()});
    if (idle_ > 0) {
      --idle_;
      ++wakeTokens_;
      poolWake_.notify_one();
    } else {
      std::thread([this] {
        // Named for top, perf and the bench's CPU breakdown (lavapipe's own are llvmpipe-N).
        ::pthread_setname_np(::pthread_self(), "worker-request");
        serveQueue();
      }).detach();
    }
  }

  // Each pushed request was given either a woken thread or a new one, and every such thread
  // looks at the queue before it sleeps again: no request waits while all threads are busy.
  void serveQueue() {
    std::unique_lock lock(poolMutex_);
    for (;;) {
      if (!queue_.empty()) {
        Queued queued = std::move(queue_.front());
        queue_.pop_front();
        lock.unlock();
        timing_.received = queued.received;
        timing_.started = std::chrono::steady_clock::now();
        handle(queued.request);
        lock.lock();
        continue;
      }
      ++idle_;
      poolWake_.wait(lock, [&] { return wakeTokens_ > 0; });
      --wakeTokens_;
    }
  }

  // `tail`: the reply's binary tail, in pieces sent as they are (a frame's pixels).
  void reply(uint64_t id, Result<json> value, std::initializer_list<std::string_view> tail = {}) {
    json head;
    head["id"] = id;
    head["ok"] = value.ok();
    if (value.ok())
      head["value"] = std::move(value.value());
    else
      head["error"] = wire::toJson(value.error());
    // Where the request's time went here: waiting for a thread, then served (the server's
    // channel counters, RendererCounters::channel).
    const auto now = std::chrono::steady_clock::now();
    if (timing_.started != std::chrono::steady_clock::time_point{})
      head["worker_us"] = {
          std::chrono::duration_cast<std::chrono::microseconds>(timing_.started - timing_.received).count(),
          std::chrono::duration_cast<std::chrono::microseconds>(now - timing_.started).count()};
    const std::string encodedHead = wire::encodeHead(head);
    std::string_view parts[3] = {encodedHead, {}, {}};
    size_t n = 1;
    for (std::string_view t : tail)
      if (n < 3) parts[n++] = t;
    std::lock_guard lock(writeMutex_);
    // A failed write means the server is gone; the reader sees end of input and exits.
    compile_protocol::writeFrameParts(channel_, {parts[0], parts[1], parts[2]});
  }

  std::shared_ptr<RenderView> view(const json& head) {
    std::lock_guard lock(viewsMutex_);
    auto it = views_.find(head.at("view").get<uint64_t>());
    return it == views_.end() ? nullptr : it->second;
  }

  template <class T, class F>
  static Result<json> map(Result<T> r, F&& f) {
    if (!r) return r.takeError();
    return json(f(r.value()));
  }

  // Reports the request whose device work overran its budget, once, and then leaves the
  // killing to the server (which restarts this process and quarantines the program). Says it
  // is alive every second meanwhile: a worker that falls silent is stopped too.
  //
  // On a CPU device (lavapipe) a budget is overrun only once the work has taken its wall time
  // AND this process has spent that much CPU time since the work started (or 3x its wall time
  // has passed, for a driver stuck without burning CPU). A machine loaded by other processes
  // stretches wall time, not CPU time: the first pass of a new program (which carries the
  // driver's JIT) ran past its wall-time budget on a heavily loaded machine and got its
  // program quarantined, while an endless loop keeps burning CPU and is caught as before.
  void watch(const RendererOptions& o) {
    const bool cpuDevice = renderer_->device().type == "cpu";
    auto lastBeat = std::chrono::steady_clock::now();
    for (;;) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      const auto now = std::chrono::steady_clock::now();
      if (now - lastBeat >= std::chrono::seconds(1)) {
        lastBeat = now;
        const std::string beat = wire::encode(wire::Message{json{{"event", "alive"}}, {}});
        std::lock_guard lock(writeMutex_);
        compile_protocol::writeFrame(channel_, beat);
      }
      json event;
      if (auto work = device_activity::oldest()) {
        const bool build = work->kind == device_activity::Kind::PipelineBuild;
        const double budget = isCheck(work->tag) ? o.checkSeconds : build ? o.buildSeconds : o.passSeconds;
        const double wall = std::chrono::duration<double>(now - work->start).count();
        const bool overrun = !cpuDevice
                                 ? wall > budget
                                 : (wall > budget && device_activity::processCpuSeconds() - work->cpuStart > budget) ||
                                       wall > kStuckFactor * budget;
        if (overrun) event = json{{"id", work->tag}, {"kind", build ? "build" : "pass"}, {"resource", "time"}};
      }
      if (event.is_null() && o.workerMemoryBytes > 0 && worker_process::residentBytes(getpid()) > o.workerMemoryBytes) {
        // Memory grows in the driver's compiles; else blame the oldest work.
        auto work = device_activity::oldest(device_activity::Kind::PipelineBuild);
        if (!work) work = device_activity::oldest();
        const bool build = work && work->kind == device_activity::Kind::PipelineBuild;
        event = json{{"id", work ? work->tag : 0},
                     {"kind", build ? "build" : "pass"},
                     {"resource", "memory"},
                     {"limit", o.workerMemoryBytes}};
      }
      if (event.is_null()) continue;
      event["event"] = "overrun";
      wire::Message m;
      m.head = std::move(event);
      const std::string bytes = wire::encode(m);
      std::lock_guard lock(writeMutex_);
      compile_protocol::writeFrame(channel_, bytes);
      return;
    }
  }

  bool isCheck(uint64_t tag) {
    std::lock_guard lock(checksMutex_);
    return checks_.count(tag) > 0;
  }

  void handle(const wire::Message& request) {
    const uint64_t id = request.head.value("id", uint64_t(0));
    device_activity::setThreadTag(id);
    // A check's submissions are long by design (millions of evaluations): their own budget.
    const bool check = request.head.value("op", std::string()).rfind("check", 0) == 0;
    if (check) {
      std::lock_guard lock(checksMutex_);
      checks_.insert(id);
    }
    try {
      handleOp(id, request.head);
    } catch (const std::exception& e) {
      reply(id, makeError(ErrorCode::Internal, std::string("render worker: malformed request: ") + e.what()));
    }
    if (check) {
      std::lock_guard lock(checksMutex_);
      checks_.erase(id);
    }
  }

  void handleOp(uint64_t id, const json& head) {
    const std::string op = head.at("op").get<std::string>();
    Renderer& r = *renderer_;
    auto noView = [&] { reply(id, makeError(ErrorCode::Internal, "render worker: no such view")); };
    if (op == "compileBrdf") {
      reply(id, map(r.compileBrdf(wire::brdfFromJson(head.at("brdf"))), [](auto& v) { return wire::toJson(v); }));
    } else if (op == "checkBrdf") {
      reply(id, map(r.checkBrdf(wire::brdfFromJson(head.at("brdf"))), [](auto& v) { return wire::toJson(v); }));
    } else if (op == "checkSampler") {
      reply(id, map(r.checkSampler(wire::brdfFromJson(head.at("brdf"))), [](auto& v) { return wire::toJson(v); }));
    } else if (op == "analysisValues") {
      reply(id, map(r.evaluateBrdf(wire::brdfFromJson(head.at("brdf")),
                                   head.at("settings").get<std::vector<ParamSetting>>(),
                                   wire::pairsFromJson(head.at("pairs"))),
                    [](auto& v) { return json(v); }));
    } else if (op == "analysisAlbedo") {
      reply(id, map(r.estimateAlbedo(wire::brdfFromJson(head.at("brdf")),
                                     head.at("settings").get<std::vector<ParamSetting>>(),
                                     head.at("views").get<std::vector<Vec3>>(), head.at("samples").get<uint32_t>()),
                    [](auto& v) { return wire::toJson(v); }));
    } else if (op == "checkEnvironmentSampler") {
      reply(id, map(r.checkEnvironmentSampler(head.at("environment").get<std::string>()),
                    [](auto& v) { return wire::toJson(v); }));
    } else if (op == "preload") {
      reply(id, map(r.preloadFromCache(wire::brdfFromJson(head.at("brdf"))), [](int n) { return n; }));
    } else if (op == "counters") {
      reply(id, wire::toJson(r.counters()));
    } else if (op == "names") {
      reply(id,
            json{{"environments", r.environmentNames()}, {"meshes", r.meshNames()}, {"textures", r.textureNames()}});
    } else if (op == "registerAsset") {
      Result<void> done = r.registerAsset(head.at("name").get<std::string>(), head.at("kind").get<AssetKind>(),
                                          head.at("path").get<std::string>());
      reply(id, done ? Result<json>(json()) : Result<json>(done.takeError()));
    } else if (op == "createView") {
      auto created = r.createView();
      if (!created) return reply(id, created.takeError());
      std::lock_guard lock(viewsMutex_);
      views_[head.at("view").get<uint64_t>()] = std::shared_ptr<RenderView>(std::move(created.value()));
      reply(id, json());
    } else if (op == "destroyView") {
      std::shared_ptr<RenderView> gone;
      {
        std::lock_guard lock(viewsMutex_);
        auto it = views_.find(head.at("view").get<uint64_t>());
        if (it != views_.end()) gone = std::move(it->second), views_.erase(it);
      }
      gone.reset();  // outside the lock: freeing device memory may wait for the view's pass
      reply(id, json());
    } else if (op == "setScene") {
      auto v = view(head);
      if (!v) return noView();
      Result<void> done = v->setScene(wire::sceneFromJson(head.at("scene")));
      reply(id, done ? Result<json>(wire::toJson(v->stats())) : Result<json>(done.takeError()));
    } else if (op == "prepareScene") {
      if (auto v = view(head)) v->prepareScene(wire::sceneFromJson(head.at("scene")));
      reply(id, json());
    } else if (op == "renderPass") {
      auto v = view(head);
      if (!v) return noView();
      const double frameTargetMs = head.value("frame_target_ms", 0.0);
      reply(id, map(v->renderPass(frameTargetMs), [](auto& s) { return wire::toJson(s); }));
    } else if (op == "interruptPass") {
      if (auto v = view(head)) v->interruptPass();
      reply(id, json());
    } else if (op == "stats") {
      auto v = view(head);
      if (!v) return noView();
      reply(id, wire::toJson(v->stats()));
    } else if (op == "readFrame") {
      auto v = view(head);
      if (!v) return noView();
      Result<Frame> frame = v->readFrame(head.at("linear").get<bool>());
      if (!frame) return reply(id, frame.takeError());
      Frame& f = frame.value();
      // Pixels travel in the binary tail: 8-bit first, then the float ones when asked.
      reply(id,
            json{{"width", f.width},
                 {"height", f.height},
                 {"linear", !f.rgba32f.empty()},
                 {"stats", wire::toJson(f.stats)}},
            {std::string_view(reinterpret_cast<const char*>(f.rgba8.data()), f.rgba8.size()),
             std::string_view(reinterpret_cast<const char*>(f.rgba32f.data()), f.rgba32f.size() * sizeof(float))});
    } else {
      reply(id, makeError(ErrorCode::Internal, "render worker: unknown operation " + op));
    }
  }

  const int channel_;
  std::shared_ptr<Renderer> renderer_;
  std::mutex poolMutex_;
  std::condition_variable poolWake_;
  struct Queued {
    wire::Message request;
    std::chrono::steady_clock::time_point received;  // read off the channel
  };
  std::deque<Queued> queue_;
  // The request this thread serves: when it was read and when this thread took it.
  struct Timing {
    std::chrono::steady_clock::time_point received, started;
  };
  static inline thread_local Timing timing_;
  int idle_ = 0;        // threads waiting for a request, not yet woken
  int wakeTokens_ = 0;  // wake-ups handed out and not yet taken
  std::mutex writeMutex_;
  std::mutex viewsMutex_;
  std::map<uint64_t, std::shared_ptr<RenderView>> views_;
  std::mutex checksMutex_;
  std::set<uint64_t> checks_;  // requests that are checks
};

}  // namespace
}  // namespace brdfa

int main() {
  using namespace brdfa;
  // A server killed without a chance to close the channel still takes its worker along.
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  keepFrameBuffersInHeap();
  // The protocol owns the channel; anything a library prints goes to stderr instead.
  const int channel = dup(0);
  dup2(2, 1);
  std::string frame;
  render_wire::Message start;
  if (!compile_protocol::readFrame(channel, frame, kMaxRequestBytes) || !render_wire::decode(frame, start)) return 1;
  render_wire::Message hello;
  hello.head["id"] = 0;
  std::shared_ptr<Renderer> renderer;
  RendererOptions options;
  try {
    options = render_wire::optionsFromJson(start.head.at("options"));
    options.isolate = false;  // this process is the isolation
    Result<std::shared_ptr<LocalRenderer>> created = LocalRenderer::create(options);
    if (created) {
      renderer = created.value();
      // Past what the budget leaves this process, the work in flight is stopped.
      if (options.workerMemoryBytes == 0 && worker_process::kMemoryBudgetsApply)
        options.workerMemoryBytes = created.value()->processMemoryLimit();
      hello.head["ok"] = true;
      hello.head["value"] = render_wire::toJson(renderer->device());
    } else {
      hello.head["ok"] = false;
      hello.head["error"] = render_wire::toJson(created.error());
    }
  } catch (const std::exception& e) {
    hello.head["ok"] = false;
    hello.head["error"] =
        render_wire::toJson(makeError(ErrorCode::Internal, std::string("render worker: ") + e.what()));
  }
  if (!compile_protocol::writeFrame(channel, render_wire::encode(hello)) || !renderer) return 1;
  Worker(channel, renderer).serve(options);
  // Detached request threads may still run: leave without destructors (the kernel frees all).
  std::fflush(stderr);
  _exit(0);
}
