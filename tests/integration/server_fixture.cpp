#include "server_fixture.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "brdfa/image_codec.h"

namespace brdfa::itest {

// ------------------------------------------------------------------------------------------

std::string readRepoFile(const std::string& relative) {
  std::ifstream in(std::string(BRDFA_SOURCE_DIR) + "/" + relative, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::unique_ptr<ServerProcess> ServerTest::server_;
std::string ServerTest::startError_;

void ServerTest::SetUpTestSuite() {
  server_ = std::make_unique<ServerProcess>();
  // A short idle timeout: sessions a test stopped watching stop rendering soon.
  startError_ = server_->start({"--idle-timeout", "3"});
}

void ServerTest::TearDownTestSuite() {
  if (server_ && server_->running()) {
    int code = server_->terminate();
    EXPECT_EQ(code, 0) << "server did not shut down cleanly on SIGTERM; log:\n" << server_->logTail();
  }
  server_.reset();
}

// A server that did not start fails every test here. A failure in SetUpTestSuite instead makes
// gtest skip the suite's tests, which ctest then reports as skipped, not failed (an ASan run
// hid three suites that way).
void ServerTest::SetUp() {
  ASSERT_TRUE(server_ && server_->running() && startError_.empty()) << "server did not start: " << startError_;
}

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

void ServerTest::expectError(const httplib::Result& r, int status, const std::string& field) {
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, status) << r->body;
  nlohmann::json body = bodyJson(r);
  ASSERT_TRUE(body.is_object()) << r->body;
  EXPECT_TRUE(body["error"].is_string()) << r->body;
  EXPECT_TRUE(body["message"].is_string()) << r->body;
  EXPECT_EQ(body.value("field", ""), field) << r->body;
}

nlohmann::json ServerTest::waitForJob(const std::string& id, std::chrono::seconds timeout) {
  using Clock = std::chrono::steady_clock;
  double lastProgress = 0;
  nlohmann::json job;
  for (auto deadline = Clock::now() + timeout; Clock::now() < deadline;) {
    auto r = get("/api/jobs/" + id);
    EXPECT_TRUE(r && r->status == 200) << id << ": " << (r ? r->body : "no answer");
    job = r ? bodyJson(r) : nlohmann::json();
    if (!job.is_object()) return job;
    double progress = job.value("progress", -1.0);
    EXPECT_GE(progress, 0.0);
    EXPECT_LE(progress, 1.0);
    EXPECT_GE(progress, lastProgress - 1e-9) << "progress never goes back";
    lastProgress = progress;
    std::string state = job.value("state", "");
    if (state != "queued" && state != "running") return job;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  ADD_FAILURE() << "job " << id << " did not finish in time: " << job.dump();
  return job;
}
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

std::string ServerTest::createSession(const nlohmann::json& scene) {
  auto r = post("/api/sessions", scene.dump());
  EXPECT_TRUE(r);
  if (!r) return {};
  EXPECT_EQ(r->status, 201) << r->body;
  return bodyJson(r).value("id", "");
}

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

// A textured Lambertian (iTexture0 scales Kd): under the furnace an object shows its texture.
const char* const kTexturedLambert = R"(analytic
::begin parameters
color Kd 1 1 1
::end parameters
::begin shader
const float kPi = 3.14159265358979323846;
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    return Kd * texture(iTexture0, texCoord).rgb / kPi;
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

// A blocking TCP connection to the server on loopback, from `source` (another loopback
// address is another client address); -1 on failure.
int connectTo(int port, const char* source) {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in from{};
  from.sin_family = AF_INET;
  ::inet_pton(AF_INET, source, &from.sin_addr);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&from), sizeof(from)) != 0) {
    ::close(fd);
    return -1;
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

bool sendAll(int fd, const std::string& bytes) {
  for (size_t off = 0; off < bytes.size();) {
    ssize_t n = ::send(fd, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
    if (n <= 0) return false;
    off += static_cast<size_t>(n);
  }
  return true;
}

// True once the server closed (or reset) the connection; reads and drops what it sent first.
bool closedByServer(int fd) {
  char buf[4096];
  for (;;) {
    ssize_t n = ::recv(fd, buf, sizeof(buf), MSG_DONTWAIT);
    if (n > 0) continue;
    if (n == 0) return true;
    return errno != EAGAIN && errno != EWOULDBLOCK;
  }
}

}  // namespace brdfa::itest
