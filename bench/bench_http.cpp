// Service-level figures through the real server on a loopback port: time from PUT of a new
// BRDF to its first frame, from a parameter change to the next frame, and frames per second
// received on the stream (what a user of the web UI waits for); and a class of 30 sessions
// streaming at once. Each with the render worker and, for comparison, --in-process.
#include "bench_http.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "brdfa/image_codec.h"

#include "bench_nonce.h"
#include "bench_util.h"
#include "class_breakdown.h"
#include "server_process.h"

namespace brdfa::bench {

namespace {

using Clock = std::chrono::steady_clock;

bool ok(const httplib::Result& r, int status = 200) { return r && r->status == status; }

struct ServiceFigures {
  double editMs = 0, sliderMs = 0, fps = 0;
  double editFullMs = 0, sliderFullMs = 0, orbitFps = 0;
  double scriptEditMs = 0, scriptSliderMs = 0;  // with no stream open: a script's wait
};

// Watches a session's stream on a connection of its own, as the web UI does: when each part
// arrived, and the scene_version and samples per pixel in its PNG's tEXt chunks.
class StreamWatcher {
 public:
  StreamWatcher(testsupport::ServerProcess& server, const std::string& path) : cli_(server.client(30)) {
    thread_ = std::thread([this, path] {
      std::string carry;
      cli_->Get(path, [&](const char* data, size_t len) {
        carry.append(data, len);
        static const std::string kSignature("\x89PNG\r\n\x1a\n", 8), kEnd = "\r\n--frame\r\n";
        for (;;) {
          const size_t begin = carry.find(kSignature);
          const size_t end = begin == std::string::npos ? begin : carry.find(kEnd, begin);
          if (end == std::string::npos) break;
          const std::vector<uint8_t> png(carry.begin() + begin, carry.begin() + end);
          Part part{Clock::now(), std::strtoull(pngText(png, "brdfa:scene_version").c_str(), nullptr, 10),
                    std::strtoull(pngText(png, "brdfa:spp").c_str(), nullptr, 10)};
          carry.erase(0, end + 2);
          std::lock_guard lock(mutex_);
          parts_.push_back(part);
          arrived_.notify_all();
        }
        return !stop_;
      });
    });
  }
  ~StreamWatcher() {
    stop_ = true;
    thread_.join();  // the next part (or the server's keep-alive) ends the read
  }
  // Milliseconds from t0 to the first part showing scene_version >= version; -1 past timeoutMs.
  double waitForVersion(uint64_t version, Clock::time_point t0, double timeoutMs) {
    std::unique_lock lock(mutex_);
    const Part* found = nullptr;
    arrived_.wait_for(lock, std::chrono::duration<double, std::milli>(timeoutMs), [&] {
      for (const Part& p : parts_)
        if (p.version >= version && p.at >= t0) return (found = &p) != nullptr;
      return false;
    });
    return found ? std::chrono::duration<double, std::milli>(found->at - t0).count() : -1;
  }
  size_t partsSince(Clock::time_point t) {
    std::lock_guard lock(mutex_);
    return size_t(std::count_if(parts_.begin(), parts_.end(), [&](const Part& p) { return p.at >= t; }));
  }

 private:
  struct Part {
    Clock::time_point at;
    uint64_t version = 0, spp = 0;
  };
  std::unique_ptr<httplib::Client> cli_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<Part> parts_;
  std::thread thread_;
};

// The figures a web UI user waits for, through a server started with `extraArgs`: a change's
// first frame on the stream (what the UI shows: a preview, RenderSettings::previewPass) and its
// first full 1-sample frame (GET /frame?min_spp=1), both timed from the request that made it.
bool measureService(const std::string& serverBinary, const std::string& sourceDir,
                    const std::vector<std::string>& extraArgs, ServiceFigures& out) {
  testsupport::ServerProcess server;
  std::string err = server.start(serverBinary, sourceDir, extraArgs);
  if (!err.empty()) {
    std::fprintf(stderr, "server: %s\n", err.c_str());
    return false;
  }
  auto cli = server.client(60);
  const std::string scene = "/api/sessions/default/scene";
  const std::string frame = "/api/sessions/default/frame?min_spp=1";
  nlohmann::json base = {
      {"environment", {{"name", "sky"}, {"visible", true}}},
      {"objects", {{{"mesh", "sphere"}, {"brdf", "ggx"}}}},
      {"render", {{"width", 512}, {"height", 512}, {"samples_per_frame", 4}, {"max_samples", 1048576}}}};
  if (!ok(cli->Put(scene, base.dump(), "application/json")) || !ok(cli->Get(frame))) {
    std::fprintf(stderr, "could not set up the default session\n");
    return false;
  }
  const std::string ggx = readText(sourceDir + "/shaders/brdfs/ggx.brdf");
  // A script's view first, with no stream open: PUT or PATCH, then GET /frame?min_spp=1 at once.
  std::vector<double> scriptEditMs, scriptSliderMs;
  for (int i = 0; i < 5; ++i) {
    const std::string name = "bench_script_" + std::to_string(i);
    const auto t0 = Clock::now();
    if (!ok(cli->Put("/api/brdfs/" + name, withUniqueFactor(ggx, "D_GGX(", 100 + i), "text/plain"), 201) ||
        !ok(cli->Patch(scene, nlohmann::json{{"objects", {{{"brdf", name}}}}}.dump(), "application/json")) ||
        !ok(cli->Get(frame)))
      return false;
    scriptEditMs.push_back(msSince(t0));
  }
  for (int i = 0; i < 11; ++i) {
    nlohmann::json patch = {{"objects", {{{"brdf", "ggx"}, {"params", {{"roughness", 0.25 + 0.05 * i}}}}}}};
    const auto t0 = Clock::now();
    if (!ok(cli->Patch(scene, patch.dump(), "application/json")) || !ok(cli->Get(frame))) return false;
    if (i > 0) scriptSliderMs.push_back(msSince(t0));  // the first switches back to ggx
  }
  out.scriptEditMs = median(scriptEditMs);
  out.scriptSliderMs = median(scriptSliderMs);

  StreamWatcher stream(server, "/api/sessions/default/stream");
  auto sceneVersion = [&]() -> uint64_t {
    auto r = cli->Get("/api/sessions/default/stats");
    return ok(r) ? nlohmann::json::parse(r->body).value("scene_version", uint64_t(0)) : 0;
  };
  // After a change made at t0: its first stream frame, then its first full frame.
  auto timeChange = [&](Clock::time_point t0, std::vector<double>& streamMs, std::vector<double>& fullMs) {
    const double shown = stream.waitForVersion(sceneVersion(), t0, 10000);
    if (shown < 0 || !ok(cli->Get(frame))) return false;
    streamMs.push_back(shown);
    fullMs.push_back(msSince(t0));
    return true;
  };

  // A new BRDF each time: a changed constant in the code, so no cache of any kind can help.
  std::vector<double> editMs, editFullMs;
  for (int i = 0; i < 5; ++i) {
    const std::string source = withUniqueFactor(ggx, "D_GGX(", i);
    const std::string name = "bench_edit_" + std::to_string(i);
    auto t0 = Clock::now();
    bool good = ok(cli->Put("/api/brdfs/" + name, source, "text/plain"), 201) &&
                ok(cli->Patch(scene, nlohmann::json{{"objects", {{{"brdf", name}}}}}.dump(), "application/json")) &&
                timeChange(t0, editMs, editFullMs);
    if (!good) {
      std::fprintf(stderr, "BRDF edit round %d failed\n%s\n", i, server.logTail().c_str());
      return false;
    }
  }

  std::vector<double> sliderMs, sliderFullMs;
  for (int i = 0; i < 11; ++i) {
    nlohmann::json patch = {{"objects", {{{"brdf", "ggx"}, {"params", {{"roughness", 0.2 + 0.05 * i}}}}}}};
    auto t0 = Clock::now();
    std::vector<double> streamMs, fullMs;
    if (!ok(cli->Patch(scene, patch.dump(), "application/json")) || !timeChange(t0, streamMs, fullMs)) return false;
    if (i == 0) continue;  // the first switches back to ggx (cached program)
    sliderMs.push_back(streamMs[0]);
    sliderFullMs.push_back(fullMs[0]);
  }

  // Frames per second on the stream over a fixed window: while the session renders on, and
  // while the camera orbits (a PATCH of the yaw every 40 ms, as a drag in the UI sends them).
  const double windowMs = 4000;
  auto t0 = Clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(windowMs));
  out.fps = stream.partsSince(t0) / (msSince(t0) / 1000.0);
  t0 = Clock::now();
  for (int i = 0; msSince(t0) < windowMs; ++i) {
    nlohmann::json patch = {{"camera", {{"yaw", 2.0 * i}}}};
    if (!ok(cli->Patch(scene, patch.dump(), "application/json"))) return false;
    std::this_thread::sleep_until(t0 + std::chrono::milliseconds(40 * (i + 1)));
  }
  out.orbitFps = stream.partsSince(t0) / (msSince(t0) / 1000.0);
  out.editMs = median(editMs);
  out.editFullMs = median(editFullMs);
  out.sliderMs = median(sliderMs);
  out.sliderFullMs = median(sliderFullMs);
  return server.terminate() == 0;
}

struct ClassFigures {
  double minFps = 0, medianFps = 0, maxFps = 0;
  double serverRssMiB = 0;
  // Where the time went over the steady part of the run (class_breakdown.h).
  ClassSnapshot before, after;
  double windowFrames = 0, windowSeconds = 0;
};

// `sessions` sessions of the default scene, each with one stream client, for `seconds`: the
// frames each received per second.
bool measureClass(const std::string& serverBinary, const std::string& sourceDir,
                  const std::vector<std::string>& extraArgs, int sessions, double seconds, ClassFigures& out) {
  testsupport::ServerProcess server;
  std::vector<std::string> args = extraArgs;
  args.insert(args.end(), {"--idle-timeout", "120"});
  if (std::string err = server.start(serverBinary, sourceDir, args); !err.empty()) {
    std::fprintf(stderr, "server: %s\n", err.c_str());
    return false;
  }
  auto cli = server.client(60);
  nlohmann::json scene = {
      {"environment", {{"name", "sky"}, {"visible", true}}},
      {"objects", {{{"mesh", "sphere"}, {"brdf", "ggx"}}}},
      {"render", {{"width", 512}, {"height", 512}, {"samples_per_frame", 4}, {"max_samples", 1048576}}}};
  std::vector<std::string> ids;
  for (int i = 0; i < sessions; ++i) {
    auto r = cli->Post("/api/sessions", scene.dump(), "application/json");
    if (!ok(r, 201)) {
      std::fprintf(stderr, "session %d: %s\n", i, r ? r->body.c_str() : "no reply");
      return false;
    }
    ids.push_back(nlohmann::json::parse(r->body).value("id", ""));
  }
  std::vector<std::atomic<int>> parts(ids.size());
  std::vector<std::thread> streams;
  const auto t0 = Clock::now();
  for (size_t i = 0; i < ids.size(); ++i) {
    streams.emplace_back([&, i] {
      auto streamCli = server.client(30);
      std::string carry;
      streamCli->Get("/api/sessions/" + ids[i] + "/stream", [&](const char* data, size_t len) {
        carry.append(data, len);
        for (size_t at; (at = carry.find("\r\n--frame\r\n")) != std::string::npos;) {
          ++parts[i];
          carry.erase(0, at + 1);
        }
        if (carry.size() > 64) carry.erase(0, carry.size() - 64);
        return msSince(t0) < seconds * 1000;
      });
    });
  }
  // The breakdown's window: after the first frames of every session, until just before the
  // streams end.
  auto framesSoFar = [&] {
    double n = 0;
    for (const std::atomic<int>& p : parts) n += p.load();
    return n;
  };
  std::this_thread::sleep_until(t0 + std::chrono::duration<double>(std::min(3.0, seconds * 0.2)));
  const double framesBefore = framesSoFar();
  const auto windowStart = Clock::now();
  out.before = takeClassSnapshot(server.pid(), server.port());
  std::this_thread::sleep_until(t0 + std::chrono::duration<double>(seconds * 0.9));
  out.after = takeClassSnapshot(server.pid(), server.port());
  out.windowSeconds = msSince(windowStart) / 1000.0;
  out.windowFrames = framesSoFar() - framesBefore;
  out.serverRssMiB = double(server.treeResidentBytes()) / (1 << 20);
  for (std::thread& t : streams) t.join();
  const double elapsed = msSince(t0) / 1000.0;
  std::vector<double> fps;
  for (const std::atomic<int>& p : parts) fps.push_back(p.load() / elapsed);
  std::sort(fps.begin(), fps.end());
  out.minFps = fps.front();
  out.maxFps = fps.back();
  out.medianFps = median(fps);
  return server.terminate() == 0;
}

// $BRDFA_BENCH_BASELINE_SERVER: another build's brdfa-server measured the same way in this run
// (with no extra flags), for ratios against an earlier version, with its own shaders and web
// files ($BRDFA_BENCH_BASELINE_ROOT, its checkout: this tree's may not match an older server's
// bindings). $BRDFA_BENCH_ROUNDS (default 1): rounds of all configurations, one after the other
// in each round, so a machine's slow phase falls on all of them; each figure is the median over
// rounds.
struct HttpBenchSettings {
  const char* baseline = nullptr;
  std::string baselineRoot;
  int rounds = 1;
};

HttpBenchSettings httpBenchSettings(const std::string& sourceDir) {
  HttpBenchSettings s;
  s.baseline = std::getenv("BRDFA_BENCH_BASELINE_SERVER");
  const char* baselineRootEnv = std::getenv("BRDFA_BENCH_BASELINE_ROOT");
  s.baselineRoot = baselineRootEnv ? baselineRootEnv : sourceDir;
  const char* roundsText = std::getenv("BRDFA_BENCH_ROUNDS");
  s.rounds = std::clamp(roundsText ? std::atoi(roundsText) : 1, 1, 50);
  return s;
}

}  // namespace

int runHttpBench(const std::string& serverBinary, const std::string& sourceDir) {
  // The same figures with the device in the supervised render worker (the default) and in the
  // server's own process (--in-process), one after the other in one run.
  const HttpBenchSettings settings = httpBenchSettings(sourceDir);
  const char* baseline = settings.baseline;
  const std::string& baselineRoot = settings.baselineRoot;
  const int rounds = settings.rounds;
  std::vector<ServiceFigures> isolatedRuns, inProcessRuns, beforeRuns;
  for (int round = 0; round < rounds; ++round) {
    // The baseline goes last in even rounds and first in odd ones, so that a machine's drift
    // during a run (a neighbour's load, its CPU's clock) does not fall on one build only.
    const bool baselineFirst = baseline && round % 2 == 1;
    ServiceFigures a, b, c;
    if ((baselineFirst && !measureService(baseline, baselineRoot, {}, c)) ||
        !measureService(serverBinary, sourceDir, {}, a) ||
        !measureService(serverBinary, sourceDir, {"--in-process"}, b) ||
        (baseline && !baselineFirst && !measureService(baseline, baselineRoot, {}, c)))
      return 1;
    isolatedRuns.push_back(a);
    inProcessRuns.push_back(b);
    beforeRuns.push_back(c);
  }
  auto medianOf = [](const std::vector<ServiceFigures>& runs) {
    auto of = [&](double ServiceFigures::*field) {
      std::vector<double> v;
      for (const ServiceFigures& f : runs) v.push_back(f.*field);
      return median(v);
    };
    return ServiceFigures{of(&ServiceFigures::editMs),       of(&ServiceFigures::sliderMs),
                          of(&ServiceFigures::fps),          of(&ServiceFigures::editFullMs),
                          of(&ServiceFigures::sliderFullMs), of(&ServiceFigures::orbitFps),
                          of(&ServiceFigures::scriptEditMs), of(&ServiceFigures::scriptSliderMs)};
  };
  const ServiceFigures isolated = medianOf(isolatedRuns), inProcess = medianOf(inProcessRuns),
                       before = medianOf(beforeRuns);
  if (rounds > 1) std::printf("(each figure: the median over %d rounds)\n", rounds);
  auto ratio = [](double a, double b) { return "ratio " + std::to_string(a / b).substr(0, 4); };
  header("Service over loopback HTTP (512x512, GGX sphere in the sky, 4 samples/pass)");
  // Each figure with --in-process and, when given, the baseline build, as ratios.
  auto rows = [&](const std::string& what, double ServiceFigures::*field, const std::string& unit,
                  const std::string& note) {
    row(what, isolated.*field, unit, note);
    row("  the same with --in-process", inProcess.*field, unit, ratio(isolated.*field, inProcess.*field));
    if (baseline) row("  the same with the baseline build", before.*field, unit, ratio(isolated.*field, before.*field));
  };
  rows("PUT new BRDF -> switch scene -> first frame on the stream", &ServiceFigures::editMs, "ms",
       "target <= 200; median of 5");
  rows("  -> first 1-sample frame (GET /frame?min_spp=1)", &ServiceFigures::editFullMs, "ms", "after the stream's");
  rows("  a script, no stream: PUT, PATCH -> first 1-sample frame", &ServiceFigures::scriptEditMs, "ms",
       "target <= 200; median of 5");
  rows("parameter change -> next frame on the stream", &ServiceFigures::sliderMs, "ms", "target <= 60; median of 10");
  rows("  -> first 1-sample frame (GET /frame?min_spp=1)", &ServiceFigures::sliderFullMs, "ms", "after the stream's");
  rows("  a script, no stream: PATCH -> first 1-sample frame", &ServiceFigures::scriptSliderMs, "ms",
       "target <= 60; median of 10");
  rows("PNG frames received on the stream", &ServiceFigures::fps, "frames/s", "target >= 20");
  rows("  while the camera orbits (a PATCH every 40 ms)", &ServiceFigures::orbitFps, "frames/s", "target >= 20");

  return runClassBench(serverBinary, sourceDir);
}

int runClassBench(const std::string& serverBinary, const std::string& sourceDir) {
  const HttpBenchSettings settings = httpBenchSettings(sourceDir);
  const char* baseline = settings.baseline;
  const std::string& baselineRoot = settings.baselineRoot;
  const int rounds = settings.rounds;
  // A class: 30 sessions streaming at once (every session should get an even share), one
  // address (the cap on connections per address raised for it).
  const std::vector<std::string> classArgs{"--max-connections-per-address", "256"};
  std::vector<std::pair<std::string, ClassFigures>> runs;
  std::vector<std::vector<ClassFigures>> perMode(3);
  for (int round = 0; round < rounds; ++round) {
    for (int turn = 0; turn < 3; ++turn) {
      // As above: the baseline build last in even rounds, first in odd ones.
      const int mode = round % 2 == 1 ? (turn + 2) % 3 : turn;
      if (mode == 2 && !baseline) continue;
      std::vector<std::string> args = mode == 2 ? std::vector<std::string>{} : classArgs;
      if (mode == 1) args.push_back("--in-process");
      ClassFigures f;
      if (!measureClass(mode == 2 ? baseline : serverBinary, mode == 2 ? baselineRoot : sourceDir, args, 30, 20, f))
        return 1;
      perMode[mode].push_back(f);
    }
  }
  for (int mode = 0; mode < 3; ++mode) {
    if (perMode[mode].empty()) continue;
    std::vector<double> lo, mid, hi, rss;
    for (const ClassFigures& f : perMode[mode]) {
      lo.push_back(f.minFps);
      mid.push_back(f.medianFps);
      hi.push_back(f.maxFps);
      rss.push_back(f.serverRssMiB);
    }
    runs.emplace_back(mode == 0   ? "render worker"
                      : mode == 1 ? "--in-process"
                                  : "baseline build",
                      ClassFigures{median(lo), median(mid), median(hi), median(rss)});
  }

  header("A class: 30 sessions streaming the default scene for 20 s");
  for (const auto& [name, f] : runs) {
    row("frames/s per session, median: " + name, f.medianFps, "frames/s",
        "slowest " + std::to_string(f.minFps).substr(0, 4) + ", fastest " + std::to_string(f.maxFps).substr(0, 4));
    row("  server and workers, resident memory", f.serverRssMiB, "MiB");
  }
  if (baseline)
    row("frames/s per session, render worker / baseline build", runs[0].second.medianFps / runs[2].second.medianFps,
        "ratio", "within 10%");
  // The last round's breakdown of each mode: where the worker loses frames against in-process.
  for (int mode = 0; mode < 2; ++mode) {
    if (perMode[mode].empty()) continue;
    const ClassFigures& f = perMode[mode].back();
    printClassBreakdown(f.before, f.after, f.windowFrames, f.windowSeconds,
                        mode == 0 ? "A class, render worker" : "A class, --in-process");
  }
  return 0;
}

}  // namespace brdfa::bench
