// The BRDF library over REST, health, static files, and process lifecycle (flags, SIGTERM).
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <thread>

#include "server_fixture.h"

namespace brdfa::itest {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

class Service : public ServerTest {};

TEST_F(Service, HealthDescribesTheDevice) {
  json h = bodyJson(get("/api/health"));
  EXPECT_EQ(h["status"], "ok");
  EXPECT_TRUE(h["device"]["name"].is_string());
  EXPECT_TRUE(h["device"]["type"] == "cpu" || h["device"]["type"] == "gpu") << h.dump();
}

TEST_F(Service, BuiltinBrdfsAreListedWithTheirParameters) {
  auto r = get("/api/brdfs");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  json list = bodyJson(r);
  ASSERT_TRUE(list.is_array());
  json ggx;
  for (const json& b : list)
    if (b["name"] == "ggx") ggx = b;
  ASSERT_TRUE(ggx.is_object()) << list.dump();
  EXPECT_EQ(ggx["builtin"], true);
  EXPECT_EQ(ggx["format"], "explorer");
  EXPECT_FALSE(ggx.contains("source"));
  for (const json& p : ggx["params"]) {
    for (const char* key : {"name", "type", "min", "max", "default"}) EXPECT_TRUE(p.contains(key)) << p.dump();
    if (p["type"] == "color") {
      EXPECT_TRUE(p["default"].is_array() && p["default"].size() == 3);
    } else if (p["type"] == "float") {
      EXPECT_TRUE(p["default"].is_number());
    } else {
      EXPECT_TRUE(p["default"].is_boolean());
    }
  }
  json one = bodyJson(get("/api/brdfs/ggx"));
  EXPECT_TRUE(one["source"].is_string());
  EXPECT_NE(one["source"].get<std::string>().find("BRDF"), std::string::npos);
}

TEST_F(Service, UserBrdfLifecycle) {
  auto v = post("/api/brdfs/validate", kLambertWhite, "text/plain");
  ASSERT_TRUE(v);
  ASSERT_EQ(v->status, 200) << v->body;
  json vb = bodyJson(v);
  EXPECT_EQ(vb["ok"], true);
  ASSERT_EQ(vb["params"].size(), 1u);
  EXPECT_EQ(vb["params"][0]["name"], "Kd");
  EXPECT_EQ(vb["params"][0]["default"], json({1, 1, 1}));
  EXPECT_TRUE(vb["warnings"].is_array());
  EXPECT_TRUE(vb["compile_ms"].is_number());

  auto r = put("/api/brdfs/itest-user_1", kLambertWhite, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 201) << r->body;
  r = put("/api/brdfs/itest-user_1", kLambertWhite, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  json got = bodyJson(get("/api/brdfs/itest-user_1"));
  EXPECT_EQ(got["source"], kLambertWhite);
  EXPECT_EQ(got["builtin"], false);
  bool listed = false;
  for (const json& b : bodyJson(get("/api/brdfs"))) listed |= b["name"] == "itest-user_1";
  EXPECT_TRUE(listed);

  // Usable in a scene by name.
  json body = furnaceScene("itest-user_1", json::object(), 16, 4);
  body["spp"] = 4;
  auto img = post("/api/render", body.dump());
  ASSERT_TRUE(img);
  EXPECT_EQ(img->status, 200) << img->body;
  EXPECT_EQ(img->get_header_value("Content-Type"), "image/png");

  auto d = del("/api/brdfs/itest-user_1");
  ASSERT_TRUE(d);
  EXPECT_EQ(d->status, 204);
  EXPECT_EQ(get("/api/brdfs/itest-user_1")->status, 404);
  EXPECT_EQ(del("/api/brdfs/itest-user_1")->status, 404);
}

TEST_F(Service, ServesTheWebUi) {
  auto r = get("/");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_NE(r->get_header_value("Content-Type").find("text/html"), std::string::npos);
  EXPECT_NE(r->body.find("<html"), std::string::npos);
  r = get("/api.js");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_NE(r->get_header_value("Content-Type").find("javascript"), std::string::npos);
  EXPECT_EQ(get("/no-such-file.js")->status, 404);
}

TEST_F(Service, StaticFilesComeGzippedWithAnEtagAndApiAnswersAreNeverCompressed) {
  std::ifstream in(std::string(BRDFA_SOURCE_DIR) + "/web/index.html", std::ios::binary);
  const std::string onDisk((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(onDisk.empty());
  auto cli = server_->client(20);
  cli->set_decompress(true);  // the client inflates gzip itself; the header says what was sent

  auto r = cli->Get("/index.html", {{"Accept-Encoding", "gzip, deflate, br"}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(r->get_header_value("Content-Encoding"), "gzip");
  EXPECT_EQ(r->body, onDisk);
  const std::string etag = r->get_header_value("ETag");
  ASSERT_FALSE(etag.empty());
  EXPECT_EQ(etag.front(), '"');

  // Unchanged since: 304 without a body, for the strong and the weak form.
  for (const std::string& tag : {etag, "W/" + etag, "\"other\", " + etag}) {
    r = cli->Get("/index.html", {{"If-None-Match", tag}});
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 304) << tag;
    EXPECT_TRUE(r->body.empty());
  }
  r = cli->Get("/index.html", {{"If-None-Match", "\"other\""}});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);

  // gzip refused (q=0) or not offered: the file as it is.
  for (const char* accept : {"gzip;q=0", "br", "identity"}) {
    r = cli->Get("/index.html", {{"Accept-Encoding", accept}});
    ASSERT_TRUE(r);
    EXPECT_EQ(r->get_header_value("Content-Encoding"), "") << accept;
    EXPECT_EQ(r->body, onDisk) << accept;
  }

  // API answers go out as they are, even to a client offering br: Debian's httplib would
  // otherwise brotli them at quality 11 on every request.
  for (const char* path : {"/api/brdfs", "/api/health", "/no-such-file.js"}) {
    r = cli->Get(path, {{"Accept-Encoding", "gzip, deflate, br"}});
    ASSERT_TRUE(r);
    EXPECT_EQ(r->get_header_value("Content-Encoding"), "") << path;
    EXPECT_FALSE(nlohmann::json::parse(r->body, nullptr, false).is_discarded()) << path;
  }
}

// ------------------------------------------------------------------------------------------
// Process lifecycle: each test runs its own server.

TEST(Lifecycle, HelpAndBadFlags) {
  auto run = [](std::vector<std::string> args) {
    pid_t pid = fork();
    if (pid == 0) {
      int devnull = ::open("/dev/null", O_WRONLY);
      ::dup2(devnull, STDOUT_FILENO);
      ::dup2(devnull, STDERR_FILENO);
      std::vector<char*> argv{const_cast<char*>(BRDFA_SERVER_BINARY)};
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  EXPECT_EQ(run({"--help"}), 0);
  EXPECT_EQ(run({"--port", "notaport"}), 2);
  EXPECT_EQ(run({"--port", "70000"}), 2);
  EXPECT_EQ(run({"--frobnicate"}), 2);
  EXPECT_EQ(run({"--threads"}), 2);
}

TEST(Lifecycle, ASecondServerOnAPortInUseExitsInsteadOfSharingIt) {
  // With SO_REUSEPORT (cpp-httplib's default) the second bind succeeded and the kernel spread
  // connections over both servers: a BRDF PUT to one was then unknown to the other.
  ServerProcess first;
  ASSERT_EQ(first.start(), "");
  const std::string port = std::to_string(first.port());
  char dataDir[] = "/tmp/brdfa-second-XXXXXX";
  ASSERT_NE(::mkdtemp(dataDir), nullptr);
  pid_t pid = fork();
  if (pid == 0) {
    int devnull = ::open("/dev/null", O_WRONLY);
    ::dup2(devnull, STDOUT_FILENO);
    ::dup2(devnull, STDERR_FILENO);
    ::execl(BRDFA_SERVER_BINARY, BRDFA_SERVER_BINARY, "--port", port.c_str(), "--root", BRDFA_SOURCE_DIR, "--data-dir",
            dataDir, static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  bool exited = false;
  for (auto deadline = Clock::now() + std::chrono::seconds(60); !exited && Clock::now() < deadline;) {
    exited = ::waitpid(pid, &status, WNOHANG) == pid;
    if (!exited) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (!exited) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
  }
  std::filesystem::remove_all(dataDir);
  ASSERT_TRUE(exited) << "a second server on port " << port << " kept running";
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << "status " << status;
  auto health = first.client()->Get("/api/health");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
}

TEST(Lifecycle, SigtermWithOpenStreamAndWaiterExitsCleanly) {
  ServerProcess server;
  std::string err = server.start({"--idle-timeout", "3"});
  ASSERT_EQ(err, "");
  // A scene that never converges during the test, a stream client, and a frame waiter.
  auto put = server.client()->Put("/api/sessions/default/scene",
                                  furnaceScene("lambert", json::object(), 32, 1 << 20, 1).dump(), "application/json");
  ASSERT_TRUE(put);
  ASSERT_EQ(put->status, 200) << put->body;

  std::atomic<size_t> streamed{0};
  std::thread streamer([&] {
    auto cli = server.client(30);
    cli->Get("/api/sessions/default/stream", httplib::Headers{}, [&](const char*, size_t len) {
      streamed += len;
      return true;
    });
  });
  std::thread waiter([&] {
    auto cli = server.client(30);
    cli->Get("/api/sessions/default/frame?min_spp=1000000000");
  });
  for (auto deadline = Clock::now() + std::chrono::seconds(10); streamed == 0 && Clock::now() < deadline;)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_GT(streamed.load(), 0u) << "stream delivered nothing";

  auto t0 = Clock::now();
  int code = server.terminate(std::chrono::seconds(20));
  EXPECT_EQ(code, 0) << server.logTail();
  EXPECT_LT(Clock::now() - t0, std::chrono::seconds(10)) << "shutdown too slow";
  streamer.join();
  waiter.join();
}

TEST(Lifecycle, DefaultSessionHasItsSceneForConcurrentFirstRequests) {
  // The default scene is applied on first use (start-up compiles nothing). Requests arriving
  // while that first application compiles must wait for it, not find a session without scene.
  ServerProcess server;
  std::string err = server.start();
  ASSERT_TRUE(err.empty()) << err;
  std::vector<int> statuses(4, 0);
  std::vector<std::string> brdfs(4);
  std::vector<std::thread> clients;
  for (int i = 0; i < 4; ++i)
    clients.emplace_back([&, i] {
      auto r = server.client()->Get("/api/sessions/default/scene");
      statuses[i] = r ? r->status : -1;
      if (r && r->status == 200) brdfs[i] = bodyJson(r)["objects"][0].value("brdf", "");
    });
  for (auto& t : clients) t.join();
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(statuses[i], 200) << "client " << i;
    EXPECT_EQ(brdfs[i], "ggx") << "client " << i;
  }
  EXPECT_EQ(server.terminate(), 0);
}

TEST_F(Service, WorkerChannelCountersAccountForEveryFrameRead) {
  constexpr int kSize = 40, kReads = 3;
  // The render worker's channel figures in /metrics, a name{labels} -> value map.
  auto workerMetrics = [] {
    std::map<std::string, double> out;
    auto r = get("/metrics");
    if (!r || r->status != 200) return out;
    std::istringstream lines(r->body);
    for (std::string line; std::getline(lines, line);)
      if (line.rfind("brdfa_worker_", 0) == 0)
        out[line.substr(0, line.rfind(' '))] = std::stod(line.substr(line.rfind(' ') + 1));
    return out;
  };
  const std::string id = createSession(furnaceScene("lambert", json::object(), kSize, 4, 4));
  ASSERT_FALSE(id.empty());
  ASSERT_EQ(get("/api/sessions/" + id + "/frame?min_spp=4")->status, 200);  // rendered and idle from here
  const auto before = workerMetrics();
  for (int i = 0; i < kReads; ++i) ASSERT_EQ(get("/api/sessions/" + id + "/frame?min_spp=4")->status, 200);
  const auto after = workerMetrics();
  auto delta = [&](const std::string& key) {
    auto a = after.find(key), b = before.find(key);
    return (a == after.end() ? 0.0 : a->second) - (b == before.end() ? 0.0 : b->second);
  };
  // One read back per frame request, and nothing else read frames meanwhile (no stream).
  EXPECT_EQ(delta(R"(brdfa_worker_requests_total{op="readFrame"})"), kReads);
  const double pixels = double(kSize) * kSize * 4;
  const double bytes = delta(R"(brdfa_worker_bytes_total{op="readFrame",direction="from"})");
  EXPECT_GE(bytes, kReads * pixels) << "each reply carries the RGBA8 frame";
  EXPECT_LE(bytes, kReads * (pixels + 2048)) << "and a small head";
  const double rt = delta(R"(brdfa_worker_request_seconds_total{op="readFrame",part="round_trip"})");
  const double queue = delta(R"(brdfa_worker_request_seconds_total{op="readFrame",part="queue"})");
  const double serve = delta(R"(brdfa_worker_request_seconds_total{op="readFrame",part="serve"})");
  EXPECT_GT(serve, 0);
  EXPECT_GE(queue, 0);
  EXPECT_GE(rt, queue + serve) << "the worker's part of a round trip is within it";
  // The in-flight integral is the sum of the requests' times in flight: here every request of
  // the window (the reads, the first scrape's tail, the second's head) is counted in both.
  double roundTrips = 0;
  for (const auto& [key, value] : after)
    if (key.find("part=\"round_trip\"") != std::string::npos)
      roundTrips += value - (before.count(key) ? before.at(key) : 0);
  const double inFlight = delta("brdfa_worker_in_flight_seconds_total");
  EXPECT_NEAR(inFlight, roundTrips, 0.02 + 0.1 * roundTrips)
      << "in flight " << inFlight << " s, round trips " << roundTrips << " s";
  EXPECT_GE(after.at("brdfa_worker_in_flight_max"), 1);
  EXPECT_EQ(del("/api/sessions/" + id)->status, 204);
}

}  // namespace
}  // namespace brdfa::itest
