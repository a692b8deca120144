// Service-level figures through the real server on a loopback port: time from PUT of a new
// BRDF to its first frame, from a parameter change to the next frame, and frames per second
// received on the stream. What a user of the web UI waits for.
#include "bench_http.h"

#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bench_util.h"
#include "bench_nonce.h"
#include "server_process.h"

namespace brdfa::bench {

namespace {

using Clock = std::chrono::steady_clock;

bool ok(const httplib::Result& r, int status = 200) { return r && r->status == status; }

}  // namespace

int runHttpBench(const std::string& serverBinary, const std::string& sourceDir) {
  testsupport::ServerProcess server;
  std::string err = server.start(serverBinary, sourceDir);
  if (!err.empty()) {
    std::fprintf(stderr, "server: %s\n", err.c_str());
    return 1;
  }
  auto cli = server.client(60);
  const std::string scene = "/api/sessions/default/scene";
  const std::string frame = "/api/sessions/default/frame?min_spp=1";
  nlohmann::json base = {{"environment", {{"name", "sky"}, {"visible", true}}},
                         {"objects", {{{"mesh", "sphere"}, {"brdf", "ggx"}}}},
                         {"render", {{"width", 512}, {"height", 512}, {"samples_per_frame", 4}, {"max_samples", 1048576}}}};
  if (!ok(cli->Put(scene, base.dump(), "application/json")) || !ok(cli->Get(frame))) {
    std::fprintf(stderr, "could not set up the default session\n");
    return 1;
  }

  // A new BRDF each time: a changed constant in the code, so no cache of any kind can help.
  const std::string ggx = readText(sourceDir + "/shaders/brdfs/ggx.brdf");
  const std::string call = "return D_GGX(";
  std::vector<double> editMs;
  for (int i = 0; i < 5; ++i) {
    std::string source = ggx;
    source.replace(source.find(call), call.size(), "return " + uniqueFactor(i) + " * D_GGX(");
    const std::string name = "bench_edit_" + std::to_string(i);
    auto t0 = Clock::now();
    bool good = ok(cli->Put("/api/brdfs/" + name, source, "text/plain"), 201) &&
                ok(cli->Patch(scene, nlohmann::json{{"objects", {{{"brdf", name}}}}}.dump(), "application/json")) &&
                ok(cli->Get(frame));
    if (!good) {
      std::fprintf(stderr, "BRDF edit round %d failed\n%s\n", i, server.logTail().c_str());
      return 1;
    }
    editMs.push_back(msSince(t0));
  }

  std::vector<double> sliderMs;
  for (int i = 0; i < 11; ++i) {
    nlohmann::json patch = {{"objects", {{{"brdf", "ggx"}, {"params", {{"roughness", 0.2 + 0.05 * i}}}}}}};
    auto t0 = Clock::now();
    if (!ok(cli->Patch(scene, patch.dump(), "application/json")) || !ok(cli->Get(frame))) return 1;
    if (i > 0) sliderMs.push_back(msSince(t0));  // the first switches back to ggx (cached program)
  }

  // Stream: count the PNG parts received in a fixed window while the session renders. A part is
  // complete when the boundary after it arrives (the next part's headers follow at once).
  int parts = 0;
  const double windowMs = 4000;
  auto streamCli = server.client(10);
  auto t0 = Clock::now();
  std::string carry;
  streamCli->Get("/api/sessions/default/stream", [&](const char* data, size_t len) {
    carry.append(data, len);
    for (size_t at; (at = carry.find("\r\n--frame\r\n")) != std::string::npos;) {
      ++parts;
      carry.erase(0, at + 1);
    }
    if (carry.size() > 64) carry.erase(0, carry.size() - 64);
    return msSince(t0) < windowMs;
  });
  const double fps = parts / (msSince(t0) / 1000.0);

  header("Service over loopback HTTP (512x512, GGX sphere in the sky, 4 samples/pass)");
  row("PUT new BRDF -> switch scene -> first frame (median of 5)", median(editMs), "ms", "target <= 200 (issue: 250)");
  row("parameter change -> next frame (median of 10)", median(sliderMs), "ms", "target <= 60");
  row("PNG frames received on the stream", fps, "frames/s", "target >= 20");
  int code = server.terminate();
  return code == 0 ? 0 : 1;
}

}  // namespace brdfa::bench
