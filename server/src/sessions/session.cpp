#include "sessions/session.h"

#include <pthread.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <string_view>

#include "brdfa/image_codec.h"
#include "brdfa/image_resample.h"

namespace brdfa::server {

namespace {
// A running mean of a frame step's time (ms) that follows changes within a few frames; the
// first measurement starts it.
void addToRunningMean(double& mean, double ms) { mean = mean > 0 ? 0.8 * mean + 0.2 * ms : ms; }

// Names the calling thread (at most 15 characters) so that top, perf and the bench's CPU
// breakdown tell a session's threads from the HTTP server's.
void nameThisThread(const char* name) { ::pthread_setname_np(::pthread_self(), name); }
}  // namespace

Session::Session(std::string id, std::unique_ptr<RenderView> view, std::chrono::milliseconds idleTimeout,
                 ServiceMetrics* metrics, SessionOwnership ownership)
    : id_(std::move(id)),
      ownership_(std::move(ownership)),
      view_(std::move(view)),
      idleTimeout_(idleTimeout),
      metrics_(metrics) {
  thread_ = std::thread([this] {
    nameThisThread("brdfa-render");
    guarded(&Session::renderLoop);
  });
  encoder_ = std::thread([this] {
    nameThisThread("brdfa-encode");
    guarded(&Session::encodeLoop);
  });
}

Session::~Session() { stop(); }

void Session::guarded(void (Session::*loop)()) {
  // An exception escaping a thread would terminate the whole server. The loops return only
  // when stopping, so after a failure (std::bad_alloc, a bug) the session records the error,
  // which stops rendering until the next scene, and the loop resumes.
  for (;;) {
    try {
      (this->*loop)();
      return;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "session %s: worker thread error: %s\n", id_.c_str(), e.what());
      std::lock_guard lock(mutex_);
      renderError_ = makeError(ErrorCode::Internal, std::string("render thread failed: ") + e.what());
      pendingRaw_.reset();
    }
    progress_.notify_all();
    frames_.notify_all();
  }
}

// Runs `f` when the scope ends, however it ends.
template <class F>
struct OnExit {
  F f;
  ~OnExit() { f(); }
};
template <class F>
OnExit(F) -> OnExit<F>;

void Session::endViewCall() {
  {
    std::lock_guard lock(mutex_);
    --pendingViewCalls_;
  }
  wake_.notify_all();
}

template <class F>
auto Session::withViewPriority(F&& call) -> decltype(call()) {
  {
    std::lock_guard lock(mutex_);
    ++pendingViewCalls_;
  }
  OnExit endCall{[this] { endViewCall(); }};
  return call();
}

void Session::setInitializer(std::function<void(Session&, std::unique_lock<std::mutex>&)> init) {
  std::lock_guard lock(sceneUpdateMutex_);
  initializer_ = std::move(init);
  initPending_ = static_cast<bool>(initializer_);
}

void Session::ensureInitialized() {
  // Without a scene, also take the update lock: another request may be applying the default
  // scene right now (it compiles for a while), and this one must wait for it, not answer
  // "no scene".
  if (initPending_.load() || !hasScene()) beginSceneUpdate(true);
}

std::unique_lock<std::mutex> Session::beginSceneUpdate(bool runInitializer) {
  std::unique_lock lock(sceneUpdateMutex_);
  if (runInitializer && initializer_) {
    // Moved out first: it runs once even if it fails to apply a scene.
    auto init = std::move(initializer_);
    initializer_ = nullptr;
    initPending_ = false;
    init(*this, lock);
  }
  return lock;
}

Result<void> Session::applyScene(std::unique_lock<std::mutex>& updateLock, const Scene& scene,
                                 nlohmann::json sceneJson) {
  if (!updateLock.owns_lock() || updateLock.mutex() != &sceneUpdateMutex_)
    return makeError(ErrorCode::Internal, "applyScene called without the scene update lock");
  // Called outside mutex_: setScene may compile for a while and must not stall stats or
  // streams. The view serializes it against the render thread's passes; the pass in progress
  // is asked to stop at its next submission, so the change waits for that, not the whole pass.
  // A session watched on a stream shows a change first by a quarter-cost preview. Nobody else
  // sees a preview (GET /frame waits for whole samples), so without a stream client it would
  // only delay the first full pass. A new program's first frame, streamed or read, is one
  // sample by the preview kernel, while the program compiles (RenderSettings::firstSampleKernel).
  Scene interactive = scene;
  interactive.render.previewPass = streamClients() > 0;
  interactive.render.firstSampleKernel = true;
  // One view call from setScene to the session taking the new scene (pendingViewCalls_): the
  // render thread starts no pass in between, else the stats read here would wait for it (a
  // first sample's), and the pass after it (a new program's first, with the driver's compile,
  // which is long on a CPU device) could start before publishRequested_ is set or a reader of the first
  // frame has asked.
  Result<void> applied = withViewPriority([&]() -> Result<void> {
    view_->interruptPass();
    Result<void> set = view_->setScene(interactive);
    if (!set) return set;
    FrameStats fresh = view_->stats();
    std::lock_guard lock(mutex_);
    hasScene_ = true;
    lastActive_ = Clock::now();
    sceneJson_ = std::move(sceneJson);
    maxSamples_ = scene.render.maxSamples;
    render_ = scene.render;
    stats_ = fresh;
    convergence_.observe(fresh);
    renderError_.reset();
    publishRequested_ = true;
    // The old scene's frame must not reach a stream client that connects now; seq is kept so
    // clients already streaming still see the next frame as newer. A frame of the old scene
    // being read or encoded still reaches those: while a user drags the camera, every frame is
    // one change behind by the time it is encoded, and dropping them left the stream nearly still.
    latest_.png.reset();
    lastRead_.reset();
    return {};
  });
  if (!applied) return applied;
  initializer_ = nullptr;  // an explicit scene supersedes a pending default
  initPending_ = false;
  wake_.notify_all();
  progress_.notify_all();
  return {};
}

bool Session::hasScene() const {
  std::lock_guard lock(mutex_);
  return hasScene_;
}

nlohmann::json Session::sceneJson() const {
  std::lock_guard lock(mutex_);
  return sceneJson_;
}

void Session::touch() {
  {
    std::lock_guard lock(mutex_);
    watchedUntil_ = std::max(watchedUntil_, Clock::now() + idleTimeout_);
    lastActive_ = Clock::now();
  }
  wake_.notify_all();
}

std::chrono::milliseconds Session::inactiveFor(Clock::time_point now) const {
  std::lock_guard lock(mutex_);
  if (streamClients_ > 0 || waiters_ > 0 || now <= lastActive_) return std::chrono::milliseconds(0);
  return std::chrono::duration_cast<std::chrono::milliseconds>(now - lastActive_);
}

FrameStats Session::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

RenderSettings Session::renderSettings() const {
  std::lock_guard lock(mutex_);
  return render_;
}

Session::Convergence Session::convergence() const {
  std::lock_guard lock(mutex_);
  return Convergence{convergence_.points(), convergence_.firstPassMs(), stats_, render_};
}

void Session::noteStatsLocked(const FrameStats& s, bool fromPass) {
  // A pass or read of a scene that was replaced meanwhile must not overwrite the new scene's
  // stats. A frame read returns the view's stats with rel_error measured afresh (the renderer
  // refreshes it on every read); it never runs a pass, so its spp is never behind a pass's.
  if (s.sceneVersion < stats_.sceneVersion) return;
  if (!fromPass && s.sceneVersion == stats_.sceneVersion && s.spp < stats_.spp) return;
  stats_ = s;
  convergence_.observe(s);
}

std::optional<Error> Session::renderError() const {
  std::lock_guard lock(mutex_);
  return renderError_;
}

bool Session::hasImage(const FrameStats& stats) { return stats.spp > 0 || stats.preview; }

bool Session::hasImageLocked() const { return hasImage(stats_); }

bool Session::watchedLocked(Clock::time_point now) const {
  return streamClients_ > 0 || waiters_ > 0 || now < watchedUntil_;
}

Result<Session::EncodedFrame> Session::waitAndEncodeFrame(uint64_t minSpp, std::chrono::milliseconds timeout, bool pfm,
                                                          WaitOutcome& outcome) {
  {
    std::unique_lock lock(mutex_);
    const uint64_t target = std::min<uint64_t>(minSpp, static_cast<uint64_t>(std::max(maxSamples_, 0)));
    auto registered = waitTargets_.insert(target);
    ++waiters_;
    wake_.notify_all();
    auto reached = [&] { return stopping_ || renderError_ || (hasScene_ && (stats_.spp >= target || stats_.done())); };
    progress_.wait_for(lock, timeout, reached);
    --waiters_;
    waitTargets_.erase(registered);
    watchedUntil_ = std::max(watchedUntil_, Clock::now() + idleTimeout_);
    if (stopping_) {
      outcome = WaitOutcome::Stopped;
      return makeError(ErrorCode::Internal, "session stopped");
    }
    outcome = renderError_ ? WaitOutcome::Failed : reached() ? WaitOutcome::Reached : WaitOutcome::TimedOut;
    if (!pfm && outcome == WaitOutcome::Reached && lastRead_ && lastRead_->passesFinished == passesFinished_ &&
        lastRead_->stats.sceneVersion == stats_.sceneVersion &&
        (lastRead_->stats.spp >= target || lastRead_->stats.done())) {
      const ReadBack read = *lastRead_;
      lock.unlock();
      return EncodedFrame{encodePng(read.rgba8->data(), read.width, read.height), read.stats};
    }
    // Become a pending view call before releasing the lock: the render thread, which checks
    // both under this lock, never sees a moment with neither and starts no pass in between.
    ++pendingViewCalls_;
  }
  OnExit endCall{[this] { endViewCall(); }};
  BRDFA_TRY_ASSIGN(Frame frame, view_->readFrame(pfm));
  const Frame& f = frame;
  {
    std::lock_guard lock(mutex_);
    noteStatsLocked(f.stats, false);
  }
  EncodedFrame out;
  out.bytes = pfm ? encodePfm(f.rgba32f.data(), f.width, f.height) : encodePng(f.rgba8.data(), f.width, f.height);
  out.stats = f.stats;
  return out;
}

void Session::addStreamClient() {
  {
    std::lock_guard lock(mutex_);
    ++streamClients_;
    publishRequested_ = true;  // a new client of a finished session still gets a frame
  }
  wake_.notify_all();
}

void Session::removeStreamClient() {
  std::lock_guard lock(mutex_);
  --streamClients_;
}

int Session::streamClients() const {
  std::lock_guard lock(mutex_);
  return streamClients_;
}

std::optional<StreamFrame> Session::waitForStreamFrame(uint64_t afterSeq, std::chrono::milliseconds timeout,
                                                       uint64_t minSceneVersion) {
  std::unique_lock lock(mutex_);
  auto fresh = [&] { return latest_.seq > afterSeq && latest_.png && latest_.sceneVersion >= minSceneVersion; };
  frames_.wait_for(lock, timeout, [&] { return stopping_ || fresh(); });
  if (stopping_ || !fresh()) return std::nullopt;
  return latest_;
}

std::optional<StreamFrame> Session::latestStreamFrame() const {
  std::lock_guard lock(mutex_);
  if (!latest_.png) return std::nullopt;
  return latest_;
}

void Session::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  progress_.notify_all();
  frames_.notify_all();
  encodeWake_.notify_all();
  std::lock_guard joinLock(joinMutex_);
  if (thread_.joinable() && thread_.get_id() != std::this_thread::get_id()) thread_.join();
  if (encoder_.joinable() && encoder_.get_id() != std::this_thread::get_id()) encoder_.join();
}

bool Session::stopped() const {
  std::lock_guard lock(mutex_);
  return stopping_;
}

void Session::publishFrame(std::unique_lock<std::mutex>& lock) {
  publishRequested_ = false;
  lastPublish_ = Clock::now();
  lock.unlock();
  const auto readStart = Clock::now();
  Result<Frame> frame = view_->readFrame(false);
  const double readMs = std::chrono::duration<double, std::milli>(Clock::now() - readStart).count();
  lock.lock();
  addToRunningMean(readMs_, readMs);
  if (!frame) {
    std::fprintf(stderr, "session %s: readFrame for stream failed: %s\n", id_.c_str(), frame.error().message.c_str());
    return;
  }
  Frame& f = frame.value();
  noteStatsLocked(f.stats, false);
  if (f.width <= 0 || f.height <= 0 || f.rgba8.size() < static_cast<size_t>(f.width) * f.height * 4) return;
  // A scene applied between the pass and this read: nothing of it to show yet (its objects
  // would be black). Its preview comes next.
  if (!hasImage(f.stats)) return;
  auto pixels = std::make_shared<const std::vector<uint8_t>>(std::move(f.rgba8));
  lastRead_ = ReadBack{pixels, f.width, f.height, f.stats, passesFinished_};
  pendingRaw_ = RawFrame{std::move(pixels), f.width, f.height, f.stats.spp, f.stats.sceneVersion, f.stats.done()};
  encodeWake_.notify_one();
}

std::vector<uint8_t> Session::encodeStreamPng(const RawFrame& raw) {
  // A stream part's headers go out before its frame exists (see the stream route), so the
  // sample count travels inside the PNG.
  const std::vector<std::pair<std::string, std::string>> text{{kSamplesPngKeyword, std::to_string(raw.spp)},
                                                              {kScenePngKeyword, std::to_string(raw.sceneVersion)}};
  // The final frame is always full size, however few samples max_samples allows.
  if (!raw.done && raw.spp < kPreviewBelowSpp && raw.width * raw.height >= kPreviewMinPixels) {
    int w = 0, h = 0;
    std::vector<uint8_t> half = halveRgba8(raw.rgba8->data(), raw.width, raw.height, w, h);
    if (!half.empty()) return encodePng(half.data(), w, h, text);
  }
  return encodePng(raw.rgba8->data(), raw.width, raw.height, text);
}

size_t Session::frameKey(const RawFrame& raw) {
  size_t key = std::hash<std::string_view>{}(
      std::string_view(reinterpret_cast<const char*>(raw.rgba8->data()), raw.rgba8->size()));
  for (uint64_t v : {uint64_t(raw.width), uint64_t(raw.height), raw.spp, raw.sceneVersion, uint64_t(raw.done)})
    key = key * 1000003u ^ std::hash<uint64_t>{}(v);
  return key;
}

void Session::encodeLoop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    if (!pendingRaw_) {
      encodeWake_.wait(lock);
      continue;
    }
    RawFrame raw = std::move(*pendingRaw_);
    pendingRaw_.reset();
    lock.unlock();
    const size_t key = frameKey(raw);
    if (key == lastEncodedKey_) {  // nothing new to show
      lock.lock();
      continue;
    }
    lastEncodedKey_ = key;
    const auto encodeStart = Clock::now();
    auto png = std::make_shared<const std::vector<uint8_t>>(encodeStreamPng(raw));
    const double encodeMs = std::chrono::duration<double, std::milli>(Clock::now() - encodeStart).count();
    lock.lock();
    addToRunningMean(encodeMs_, encodeMs);
    latest_.png = std::move(png);
    latest_.seq += 1;
    latest_.spp = raw.spp;
    latest_.sceneVersion = raw.sceneVersion;
    frames_.notify_all();
  }
}

void Session::renderLoop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    bool canRender = hasScene_ && !renderError_;
    const Clock::time_point now = Clock::now();
    // A waiter whose samples are there reads next: no new pass may slip in before its read.
    bool waiterSatisfied = !waitTargets_.empty() && stats_.spp >= *waitTargets_.begin();
    // A first sample stands for kFirstPassGrace unless a reader waits for more samples.
    const Clock::time_point graceEnd = provisionalSince_ + kFirstPassGrace;
    const bool inGrace = stats_.provisional && waitTargets_.empty() && now < graceEnd;
    bool wantPass =
        canRender && !stats_.done() && watchedLocked(now) && pendingViewCalls_ == 0 && !waiterSatisfied && !inGrace;
    bool wantPublish =
        canRender && streamClients_ > 0 && publishRequested_ && hasImageLocked() && pendingViewCalls_ == 0;
    if (!wantPass && !wantPublish) {
      // Nothing to do until a scene change, a watcher, a stream client or stop (or the grace's
      // end). A watched-until deadline needs no timed wake: it only ever turns rendering off,
      // checked after each pass.
      if (inGrace)
        wake_.wait_until(lock, graceEnd);
      else
        wake_.wait(lock);
      continue;
    }
    // A preview or first sample not yet shown is read first: the pass after it can be long (a
    // new program's first, with the driver's compile).
    if (wantPass && !(wantPublish && (stats_.preview || stats_.provisional))) {
      uint64_t versionBefore = stats_.sceneVersion;
      const uint64_t sppBefore = stats_.spp, passesBefore = stats_.passes;
      const bool previewBefore = stats_.preview;
      const uint64_t pixels = uint64_t(std::max(render_.width, 0)) * uint64_t(std::max(render_.height, 0));
      // The pass, the read and the loop's own small share within one stream frame interval;
      // never below kFrameWorkShare times the frame's read and encode, nor 5 ms.
      const double frameTargetMs =
          streamClients_ > 0 ? std::max({kStreamFrameMs - readMs_ - 2.0, kFrameWorkShare * (readMs_ + encodeMs_), 5.0})
                             : 0.0;
      lock.unlock();
      Result<FrameStats> pass = view_->renderPass(frameTargetMs);
      lock.lock();
      if (!pass) {
        // Only an error of the scene still in place counts; a newer scene gets a fresh try.
        if (stats_.sceneVersion == versionBefore) {
          std::fprintf(stderr, "session %s: render pass failed: %s\n", id_.c_str(), pass.error().message.c_str());
          renderError_ = pass.takeError();
        }
        progress_.notify_all();
        frames_.notify_all();
        continue;
      }
      if (metrics_) {
        metrics_->passTime.add(pass->lastPassMs / 1000.0);
        // The pass's own samples; a scene applied meanwhile restarted the count from 0.
        const uint64_t spp =
            pass->sceneVersion == versionBefore && pass->spp >= sppBefore ? pass->spp - sppBefore : pass->spp;
        metrics_->samplesRendered += spp * pixels;
      }
      noteStatsLocked(pass.value(), true);
      ++passesFinished_;
      if (pass->provisional) provisionalSince_ = Clock::now();
      progress_.notify_all();
      bool due = publishRequested_ || stats_.done() || Clock::now() - lastPublish_ >= kPublishInterval;
      // A pass interrupted for a scene change (RenderView::interruptPass) added nothing to show
      // (the change comes next). One that returned at its frame target has (passInProgress).
      const bool progressed = pass->passes != passesBefore || pass->spp != sppBefore ||
                              pass->preview != previewBefore || pass->passInProgress;
      if (streamClients_ > 0 && hasImageLocked() && due && progressed) publishFrame(lock);
    } else {
      publishFrame(lock);
    }
  }
}

}  // namespace brdfa::server
