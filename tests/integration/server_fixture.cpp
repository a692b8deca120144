#include "server_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "brdfa/image_codec.h"

namespace brdfa::itest {

namespace {

using Clock = std::chrono::steady_clock;

// Reads one '\n'-terminated line from `fd` within `timeout`.
bool readLine(int fd, std::string& line, std::chrono::milliseconds timeout) {
  auto deadline = Clock::now() + timeout;
  line.clear();
  while (Clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    int left = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
    int n = ::poll(&p, 1, std::max(left, 1));
    if (n <= 0) continue;
    char c;
    ssize_t got = ::read(fd, &c, 1);
    if (got <= 0) return false;  // EOF: the server exited
    if (c == '\n') return true;
    line += c;
  }
  return false;
}

}  // namespace

ServerProcess::~ServerProcess() {
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    int status = 0;
    ::waitpid(pid_, &status, 0);
  }
  if (stdoutFd_ >= 0) ::close(stdoutFd_);
  if (!tmpDir_.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(tmpDir_, ec);
  }
}

std::string ServerProcess::logTail(size_t bytes) const {
  std::ifstream in(tmpDir_ + "/server.log", std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  return s.size() > bytes ? "..." + s.substr(s.size() - bytes) : s;
}

std::string ServerProcess::start(const std::vector<std::string>& extraArgs) {
  char tmpl[] = "/tmp/brdfa-itest-XXXXXX";
  if (!::mkdtemp(tmpl)) return "mkdtemp failed";
  tmpDir_ = tmpl;
  std::string dataDir = tmpDir_ + "/data";
  std::string logPath = tmpDir_ + "/server.log";

  std::vector<std::string> args = {BRDFA_SERVER_BINARY, "--port",     "0",    "--root",
                                   BRDFA_SOURCE_DIR,    "--data-dir", dataDir};
  args.insert(args.end(), extraArgs.begin(), extraArgs.end());

  int out[2];
  if (::pipe(out) != 0) return "pipe failed";
  pid_t pid = ::fork();
  if (pid < 0) return "fork failed";
  if (pid == 0) {
    ::dup2(out[1], STDOUT_FILENO);
    int log = ::open(logPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (log >= 0) ::dup2(log, STDERR_FILENO);
    ::close(out[0]);
    ::close(out[1]);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(out[1]);
  pid_ = pid;
  stdoutFd_ = out[0];

  std::string line;
  if (!readLine(stdoutFd_, line, std::chrono::seconds(60)))
    return "no `listening on` line within 60 s; server log:\n" + logTail();
  const std::string prefix = "listening on http://127.0.0.1:";
  if (line.rfind(prefix, 0) != 0) return "unexpected first line: '" + line + "'";
  port_ = std::atoi(line.c_str() + prefix.size());
  if (port_ <= 0) return "no port in: '" + line + "'";

  auto cli = client(5);
  for (auto deadline = Clock::now() + std::chrono::seconds(30); Clock::now() < deadline;) {
    auto r = cli->Get("/api/health");
    if (r && r->status == 200) return "";
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return "/api/health never answered 200; server log:\n" + logTail();
}

int ServerProcess::terminate(std::chrono::seconds timeout) {
  if (pid_ <= 0) return -1;
  ::kill(pid_, SIGTERM);
  int status = 0;
  auto deadline = Clock::now() + timeout;
  for (;;) {
    pid_t r = ::waitpid(pid_, &status, WNOHANG);
    if (r == pid_) break;
    if (Clock::now() > deadline) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
      pid_ = -1;
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  pid_ = -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::unique_ptr<httplib::Client> ServerProcess::client(int readTimeoutSec) const {
  auto cli = std::make_unique<httplib::Client>("127.0.0.1", port_);
  cli->set_connection_timeout(5);
  cli->set_read_timeout(readTimeoutSec);
  cli->set_write_timeout(30);
  return cli;
}

// ------------------------------------------------------------------------------------------

std::unique_ptr<ServerProcess> ServerTest::server_;
std::string ServerTest::startError_;

void ServerTest::SetUpTestSuite() {
  server_ = std::make_unique<ServerProcess>();
  // A short idle timeout: sessions a test stopped watching stop rendering soon.
  startError_ = server_->start({"--idle-timeout", "3"});
  if (!startError_.empty()) ADD_FAILURE() << "server did not start: " << startError_;
}

void ServerTest::TearDownTestSuite() {
  if (server_ && server_->running()) {
    int code = server_->terminate();
    EXPECT_EQ(code, 0) << "server did not shut down cleanly on SIGTERM; log:\n" << server_->logTail();
  }
  server_.reset();
}

void ServerTest::SetUp() { ASSERT_TRUE(server_ && server_->running() && startError_.empty()) << startError_; }

void ServerTest::TearDown() {
  if (!server_ || !server_->running()) return;
  // Whatever the test sent, the server must still answer.
  auto r = get("/api/health");
  ASSERT_TRUE(r) << "server unreachable after the test; log:\n" << server_->logTail();
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(bodyJson(r).value("status", ""), "ok");
  if (HasFailure()) std::fprintf(stderr, "---- server log tail ----\n%s\n", server_->logTail(3000).c_str());
}

httplib::Result ServerTest::get(const std::string& path) { return server_->client()->Get(path); }
httplib::Result ServerTest::post(const std::string& path, const std::string& body, const std::string& type) {
  return server_->client()->Post(path, body, type);
}
httplib::Result ServerTest::put(const std::string& path, const std::string& body, const std::string& type) {
  return server_->client()->Put(path, body, type);
}
httplib::Result ServerTest::patch(const std::string& path, const std::string& body) {
  return server_->client()->Patch(path, body, "application/merge-patch+json");
}
httplib::Result ServerTest::del(const std::string& path) { return server_->client()->Delete(path); }

nlohmann::json bodyJson(const httplib::Result& r) {
  if (!r) return nullptr;
  return nlohmann::json::parse(r->body, nullptr, /*allow_exceptions=*/false);
}

bool decodeImage(const std::string& body, Image& out) {
  std::vector<uint8_t> bytes(body.begin(), body.end());
  return brdfa::decodePfm(bytes, out.width, out.height, out.rgba);
}

std::vector<std::pair<int, int>> interiorPixels(const Image& img) {
  std::vector<std::pair<int, int>> out;
  for (int y = 1; y + 1 < img.height; ++y)
    for (int x = 1; x + 1 < img.width; ++x) {
      bool all = true;
      for (int dy = -1; dy <= 1 && all; ++dy)
        for (int dx = -1; dx <= 1 && all; ++dx)
          if (!(img.lum(x + dx, y + dy) != 0.0f)) all = false;
      if (all) out.emplace_back(x, y);
    }
  return out;
}

nlohmann::json furnaceScene(const std::string& brdf, const nlohmann::json& params, int size, int maxSamples,
                            int samplesPerFrame) {
  return {{"environment", {{"name", "furnace"}, {"visible", false}}},
          {"objects", nlohmann::json::array({{{"mesh", "sphere"}, {"brdf", brdf}, {"params", params}}})},
          {"render",
           {{"width", size}, {"height", size}, {"max_samples", maxSamples}, {"samples_per_frame", samplesPerFrame}}}};
}

const char* const kLambertWhite = R"(analytic
# white Lambertian: reflects all light, so the white furnace renders exactly 1
::begin parameters
color Kd 1 1 1
::end parameters
::begin shader
const float kMyPi = 3.14159265358979323846;
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    return Kd / kMyPi;
}
::end shader
)";

// Line 9 of this text is the broken one.
const char* const kSyntaxErrorOnLine9 = R"(analytic
::begin parameters
float a 0 1 0.5
::end parameters
::begin shader
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    float x = a;
    return vec3(x) + * ;
}
::end shader
)";

// NaN wherever L.x > 0: sqrt of a negative value the compiler cannot fold away.
const char* const kNanOnHalfHemisphere = R"(analytic
::begin parameters
float scale 0 1 1
::end parameters
::begin shader
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    if (L.x > 0.0) return vec3(sqrt(L.x - 2.0));
    return vec3(scale / 3.14159265);
}
::end shader
)";

}  // namespace brdfa::itest
