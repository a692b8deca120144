// An interactive session: one RenderView, its scene (as JSON and as brdfa::Scene), a render
// thread that runs progressive passes only while the scene is not done (FrameStats::done():
// converged to render.target_error, or max_samples reached) and somebody watches
// (a stream client, a frame waiter, or a frame/stats request within the idle timeout), and an
// encoder thread that turns frames read back for stream clients into PNGs. Otherwise both
// sleep on condition variables, so a finished or unwatched session costs no CPU.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "brdfa/renderer.h"
#include "jobs/convergence.h"
#include "metrics/metrics.h"

namespace brdfa::server {

// The latest PNG published for stream clients. `seq` grows with every publication.
struct StreamFrame {
  std::shared_ptr<const std::vector<uint8_t>> png;  // may be a half-size preview (Session::kPreviewBelowSpp)
  uint64_t seq = 0;
  uint64_t spp = 0;
  uint64_t sceneVersion = 0;  // FrameStats::sceneVersion of the image
};

// Who a session belongs to, fixed when it is made.
struct SessionOwnership {
  std::string user;         // identity.h's Identity::owner(); "" for `default` and in none mode
  std::string displayName;  // theirs at creation, for the teacher's class view
  // Reads the session's frames and stream without a token (an <img> cannot send one): 128
  // random bits, made by SessionManager::create.
  std::string viewKey;
};

class Session {
 public:
  using Clock = std::chrono::steady_clock;

  // `metrics`, when given, counts each pass's time and pixel samples; it must outlive the session.
  Session(std::string id, std::unique_ptr<RenderView> view, std::chrono::milliseconds idleTimeout,
          ServiceMetrics* metrics = nullptr, SessionOwnership ownership = {});
  ~Session();  // stop()
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const std::string& id() const { return id_; }
  const SessionOwnership& ownership() const { return ownership_; }
  const std::string& owner() const { return ownership_.user; }

  // --- Scene. Updates are serialized by a lock the caller holds across read-modify-write
  // (PATCH reads the current JSON, merges, validates, applies).

  // A deferred first scene (the default session's): it runs on the first beginSceneUpdate
  // that asks for it, so nothing is compiled at server start.
  void setInitializer(std::function<void(Session&, std::unique_lock<std::mutex>&)> init);

  // Locks scene updates. With `runInitializer`, a pending initializer runs first (callers that
  // read the current scene need it; a PUT that replaces it does not).
  std::unique_lock<std::mutex> beginSceneUpdate(bool runInitializer = true);

  // Runs a pending initializer; cheap (no lock) once there is none. Readers call this first.
  void ensureInitialized();

  // view->setScene under the update lock; on success stores scene and JSON, resets progress
  // and wakes the render thread. On error nothing changes (the renderer keeps the old scene).
  Result<void> applyScene(std::unique_lock<std::mutex>& updateLock, const Scene& scene, nlohmann::json sceneJson);

  bool hasScene() const;
  nlohmann::json sceneJson() const;  // null until a scene was applied

  // --- Progress.

  // Marks the session watched for the idle timeout (frame and stats requests).
  void touch();
  // How long nobody has used the session: 0 while a stream or a frame wait is open, else the
  // time since its creation, its last scene change or its last touch(), whichever is latest.
  std::chrono::milliseconds inactiveFor(Clock::time_point now) const;
  FrameStats stats() const;               // as of the latest pass or frame read; never blocks on the device
  RenderSettings renderSettings() const;  // of the scene in place (target_error, sampling)

  // The error-against-time series since the last accumulation restart (see convergence.h),
  // with the stats and render settings of the same moment.
  struct Convergence {
    std::vector<ConvergencePoint> points;
    double firstPassMs = 0;  // ConvergenceSeries::firstPassMs
    FrameStats stats;
    RenderSettings render;
  };
  Convergence convergence() const;
  std::optional<Error> renderError() const;

  enum class WaitOutcome { Reached, TimedOut, Stopped, Failed };
  // Waits until spp >= min(minSpp, max_samples), rendering is done (converged to
  // render.target_error, or max_samples reached: FrameStats::done()), rendering failed, the
  // session stopped, or `timeout` passed (counting as a watcher meanwhile), then reads the frame
  // without letting the render thread start another pass in between: the pass that satisfied
  // the wait is the one whose frame is read. `outcome` tells how the wait ended; on Stopped no
  // frame is read.
  // The frame is encoded (PNG, or PFM when `pfm`) before rendering resumes: on a CPU device the
  // encoder and the render passes would share the cores, and the encode took several times longer.
  struct EncodedFrame {
    std::vector<uint8_t> bytes;
    FrameStats stats;
  };
  Result<EncodedFrame> waitAndEncodeFrame(uint64_t minSpp, std::chrono::milliseconds timeout, bool pfm,
                                          WaitOutcome& outcome);

  // --- Streaming.
  void addStreamClient();
  void removeStreamClient();
  int streamClients() const;
  // The latest published frame when its seq is greater than `afterSeq` and it shows scene
  // version `minSceneVersion` or later; waits up to `timeout` for one. nullopt on timeout or stop.
  std::optional<StreamFrame> waitForStreamFrame(uint64_t afterSeq, std::chrono::milliseconds timeout,
                                                uint64_t minSceneVersion = 0);
  std::optional<StreamFrame> latestStreamFrame() const;

  // Stops the render thread and wakes every waiter; idempotent. Streams end on their next wake.
  void stop();
  bool stopped() const;

  // Minimum interval between published stream frames (about 30 per second).
  static constexpr std::chrono::milliseconds kPublishInterval{33};
  // After a new program's first sample, how long its first pass waits for a further scene
  // change unless a reader asks for more samples. That pass carries the driver's JIT of the
  // whole program, which nothing interrupts and which is long on a CPU device; a script that posts
  // BRDFs in a loop makes its next change soon after reading the first sample, and would
  // otherwise wait for that JIT of a program it no longer uses.
  static constexpr std::chrono::milliseconds kFirstPassGrace{80};
  // The frame interval a streamed session aims at: while a stream client watches, each pass is
  // sized to it less the time a frame's read takes (RenderView::renderPass's frame target).
  // Unwatched, passes keep samples_per_frame. docs/design.md section 9 asks for at least 20 frames/s;
  // a shorter interval leaves a margin for passes that overrun their plan (the encoder thread and the
  // render worker's round trips share two cores with the device's threads). Where one sample
  // is longer than the frame (mis on a large image on a small CPU device), what keeps the still
  // stream near the goal is showing passes partway (RenderView::renderPass), not this margin.
  static constexpr double kStreamFrameMs = 42.0;
  // A frame's read and encode take at most about 1 / (1 + kFrameWorkShare) of a watched
  // session's time: a large image's frames (whose read and encode are long on a CPU device)
  // get longer passes instead of taking the CPU from rendering at the full frame rate.
  static constexpr double kFrameWorkShare = 2.0;
  // Stream frames with fewer samples than this (the first passes after a change: 1, then 3)
  // are sent at half resolution when the frame has at least kPreviewMinPixels and is not the
  // final (done) one: they are mostly noise, and the full-size PNG of noise is what costs the most
  // to encode, send and decode. A progressive preview, as in Cycles' viewport; the <img> scales
  // it to the view. /frame always answers full size.
  static constexpr uint64_t kPreviewBelowSpp = 4;
  static constexpr int kPreviewMinPixels = 256 * 256;
  // tEXt keywords of each stream PNG: its samples per pixel (0 for a preview,
  // RenderSettings::previewPass) and the scene_version it shows (as in the stats).
  static constexpr const char* kSamplesPngKeyword = "brdfa:spp";
  static constexpr const char* kScenePngKeyword = "brdfa:scene_version";

 private:
  void renderLoop();
  void encodeLoop();
  void guarded(void (Session::*loop)());
  bool watchedLocked(Clock::time_point now) const;
  static bool hasImage(const FrameStats& stats);  // a pass or a preview is there to show
  bool hasImageLocked() const;                    // hasImage(stats_)
  void publishFrame(std::unique_lock<std::mutex>& lock);
  // Takes the stats of a pass or a frame read of the scene in place (older scenes' are dropped)
  // and feeds the convergence series. Under mutex_.
  void noteStatsLocked(const FrameStats& stats, bool fromPass);
  // Runs a view call from a request thread. The view serializes calls with a plain mutex,
  // which is not fair: a render thread that starts the next pass right after the last would
  // starve readFrame/setScene. The render thread holds off while such calls are pending.
  template <class F>
  auto withViewPriority(F&& call) -> decltype(call());
  void endViewCall();  // ends one pending view call and wakes the render thread

  const std::string id_;
  const SessionOwnership ownership_;
  const std::unique_ptr<RenderView> view_;
  const std::chrono::milliseconds idleTimeout_;
  ServiceMetrics* const metrics_;

  std::mutex sceneUpdateMutex_;  // order: sceneUpdateMutex_ before mutex_
  std::function<void(Session&, std::unique_lock<std::mutex>&)> initializer_;
  std::atomic<bool> initPending_{false};

  mutable std::mutex mutex_;
  std::condition_variable wake_;      // render thread: scene changed, watched, stream added, stop
  std::condition_variable progress_;  // frame waiters: a pass finished
  std::condition_variable frames_;    // stream clients: a frame was published
  bool stopping_ = false;
  bool hasScene_ = false;
  nlohmann::json sceneJson_;
  int maxSamples_ = 0;
  RenderSettings render_;
  FrameStats stats_;
  ConvergenceSeries convergence_;
  std::optional<Error> renderError_;
  Clock::time_point watchedUntil_{};
  Clock::time_point lastActive_ = Clock::now();  // creation, scene change or touch()
  int waiters_ = 0;
  std::multiset<uint64_t> waitTargets_;  // spp each waitAndEncodeFrame caller waits for
  int pendingViewCalls_ = 0;
  int streamClients_ = 0;
  bool publishRequested_ = false;
  Clock::time_point lastPublish_{};
  double readMs_ = 0;    // running mean of a stream frame's read (publishFrame), ms
  double encodeMs_ = 0;  // running mean of a stream frame's PNG encode (encodeLoop), ms
  StreamFrame latest_;
  // A frame read back for the stream, waiting for the encoder thread. Only the newest is kept:
  // when encoding falls behind, older frames are dropped rather than queued.
  struct RawFrame {
    std::shared_ptr<const std::vector<uint8_t>> rgba8;  // shared with lastRead_
    int width = 0, height = 0;
    uint64_t spp = 0, sceneVersion = 0;
    bool done = false;  // the final frame (FrameStats::done())
  };
  // The stream PNG of `raw`: a half-size preview below kPreviewBelowSpp, its spp in a tEXt chunk.
  static std::vector<uint8_t> encodeStreamPng(const RawFrame& raw);
  // A hash of the frame's pixels and what its PNG says (size, samples, scene, final).
  static size_t frameKey(const RawFrame& raw);
  std::optional<RawFrame> pendingRaw_;
  std::condition_variable encodeWake_;
  // The last frame read for the stream, and passesFinished_ when it was read. Until another pass
  // finishes it is what a read of the view would return, so a reader whose target it meets
  // gets it without a view call, which would wait for the pass in flight (after a first
  // sample: a new program's first, with the driver's JIT).
  struct ReadBack {
    std::shared_ptr<const std::vector<uint8_t>> rgba8;
    int width = 0, height = 0;
    FrameStats stats;
    uint64_t passesFinished = 0;
  };
  std::optional<ReadBack> lastRead_;
  uint64_t passesFinished_ = 0;  // render passes returned, of any scene
  // When the current first sample (FrameStats::provisional) finished: the program's first pass
  // waits until kFirstPassGrace after it (Session::renderLoop).
  Clock::time_point provisionalSince_{};
  // frameKey of what the encoder last published (encodeLoop only; 0: nothing yet): a frame
  // equal to it is not sent again. A pass shown partway before any of its tiles finished reads
  // back the same image.
  size_t lastEncodedKey_ = 0;

  std::mutex joinMutex_;  // DELETE and server shutdown may both stop a session; one joins

  // Last: they start after every member above is constructed. PNG encoding runs on its own
  // thread so the render thread goes on with the next pass meanwhile.
  std::thread thread_;
  std::thread encoder_;
};

}  // namespace brdfa::server
