#include "bench_measured.h"

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "bench_util.h"
#include "brdfa/measured.h"
#include "merl_files.h"
#include "server_process.h"

namespace brdfa::bench {

namespace {

using Clock = std::chrono::steady_clock;

bool created(const httplib::Result& r) { return r && r->status == 201; }

}  // namespace

int runMeasuredBench(const std::string& serverBinary, const std::string& sourceDir, int rounds) {
  const std::string ggx = testsupport::ggxMerl(0.3, {0.95, 0.64, 0.54});
  std::vector<double> readMs;
  for (int i = 0; i < rounds; ++i) {
    const auto t0 = Clock::now();
    auto table = readMerl(ggx);
    readMs.push_back(msSince(t0));
    if (!table) {
      std::fprintf(stderr, "readMerl: %s\n", table.error().message.c_str());
      return 1;
    }
  }

  testsupport::ServerProcess server;
  if (std::string err = server.start(serverBinary, sourceDir, {}); !err.empty()) {
    std::fprintf(stderr, "server: %s\n", err.c_str());
    return 1;
  }
  auto cli = server.client(120);
  auto assetsBytes = [&] {
    auto h = cli->Get("/api/health");
    return h ? nlohmann::json::parse(h->body)["memory"]["renderer"].value("assets_bytes", 0.0) : 0.0;
  };
  const double before = assetsBytes();
  // The upload's round trip: the body sent, the table checked, stored, read and put on the
  // device; at 201 the id is usable in scenes.
  std::vector<double> uploadMs, frameMs;
  std::string id;
  const int uploads = std::max(3, rounds / 3);
  // The body is made once, before the clock starts: what is timed is the server's part and the
  // transfer, not the client building a 35 MB string.
  const std::string boundary = "brdfa-bench-boundary-7d1f";
  const std::string body = "--" + boundary +
                           "\r\nContent-Disposition: form-data; name=\"file\"; filename=\"ggx.binary\"\r\n"
                           "Content-Type: application/octet-stream\r\n\r\n" +
                           ggx + "\r\n--" + boundary + "--\r\n";
  for (int i = 0; i < uploads; ++i) {
    const auto t0 = Clock::now();
    auto r = cli->Post("/api/assets", body, "multipart/form-data; boundary=" + boundary);
    uploadMs.push_back(msSince(t0));
    if (!created(r)) {
      std::fprintf(stderr, "upload: %s\n", r ? r->body.c_str() : "no answer");
      return 1;
    }
    id = nlohmann::json::parse(r->body).value("id", "");
  }
  const double perTable = (assetsBytes() - before) / uploads;
  // A scene switching between the analytic GGX and the table: PATCH to the first 1-sample frame.
  for (int i = 0; i < 2 * uploads; ++i) {
    const std::string brdf = i % 2 ? "ggx" : id;
    nlohmann::json scene = {{"environment", {{"name", "sky"}}},
                            {"objects", {{{"mesh", "sphere"}, {"brdf", brdf}}}},
                            {"render", {{"width", 512}, {"height", 512}, {"samples_per_frame", 4}}}};
    const auto t0 = Clock::now();
    auto put = cli->Put("/api/sessions/default/scene", scene.dump(), "application/json");
    auto frame = cli->Get("/api/sessions/default/frame?min_spp=1");
    if (!put || put->status != 200 || !frame || frame->status != 200) {
      std::fprintf(stderr, "scene: %s\n", put ? put->body.c_str() : "no answer");
      return 1;
    }
    if (i > 1 && i % 2 == 0) frameMs.push_back(msSince(t0));  // the first compiles the program
  }
  server.terminate();

  header("Measured BRDFs (a 35 MB MERL table made from GGX)");
  row("readMerl: parse and check the 35 MB file", median(readMs), "ms", "target < 1000");
  row("POST /api/assets -> 201, the table usable in scenes", median(uploadMs), "ms",
      "target < 1000; loopback, median of " + std::to_string(uploads));
  row("  the table in the renderer's memory (assets_bytes)", perTable / (1 << 20), "MiB", "3 floats a bin");
  row("scene switched to the table -> first 1-sample frame", median(frameMs), "ms",
      "512x512 sky; the program already built");
  return 0;
}

}  // namespace brdfa::bench
