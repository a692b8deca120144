// Test harness for the integration suite: runs the real brdfa-server binary on a loopback port
// (--port 0), reads its `listening on` line, and stops it with SIGTERM, reporting the exit
// status so a test can insist on a clean shutdown.
#pragma once

#include <gtest/gtest.h>
#include <httplib.h>
#include <sys/types.h>

#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace brdfa::itest {

class ServerProcess {
 public:
  ServerProcess() = default;
  ~ServerProcess();  // kills a server still running
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  // Starts BRDFA_SERVER_BINARY --port 0 --root BRDFA_SOURCE_DIR --data-dir <fresh temp dir>
  // plus `extraArgs`, waits for the listening line and a healthy /api/health. Returns "" on
  // success, else why it failed (with the server log).
  std::string start(const std::vector<std::string>& extraArgs = {});

  // SIGTERM, then waits up to `timeout` for exit. Returns the exit code; -1 if it died by a
  // signal or had to be killed after the timeout.
  int terminate(std::chrono::seconds timeout = std::chrono::seconds(30));

  bool running() const { return pid_ > 0; }
  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  std::string logTail(size_t bytes = 6000) const;  // the server's stderr

  std::unique_ptr<httplib::Client> client(int readTimeoutSec = 120) const;

 private:
  pid_t pid_ = -1;
  int port_ = 0;
  int stdoutFd_ = -1;
  std::string tmpDir_;
};

// A test suite sharing one server. Each derived suite starts its own server and, at the end,
// stops it and expects exit status 0. After every test the server must still be healthy.
class ServerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite();
  static void TearDownTestSuite();
  void SetUp() override;
  void TearDown() override;

  static httplib::Result get(const std::string& path);
  static httplib::Result post(const std::string& path, const std::string& body,
                              const std::string& type = "application/json");
  static httplib::Result put(const std::string& path, const std::string& body,
                             const std::string& type = "application/json");
  static httplib::Result patch(const std::string& path, const std::string& body);
  static httplib::Result del(const std::string& path);

  static std::unique_ptr<ServerProcess> server_;
  static std::string startError_;
};

// Parses a response body as JSON (null when it is not JSON).
nlohmann::json bodyJson(const httplib::Result& r);

// Decoded PFM body.
struct Image {
  int width = 0, height = 0;
  std::vector<float> rgba;
  float at(int x, int y, int c) const { return rgba[(static_cast<size_t>(y) * width + x) * 4 + c]; }
  float lum(int x, int y) const { return (at(x, y, 0) + at(x, y, 1) + at(x, y, 2)) / 3.0f; }
};
bool decodeImage(const std::string& pfmBody, Image& out);

// Pixels whose 3x3 neighbourhood is all non-zero: on the object and away from its silhouette.
std::vector<std::pair<int, int>> interiorPixels(const Image& img);

// Sources used by several tests.
extern const char* const kLambertWhite;  // color Kd 1 1 1, f = Kd / pi (own PI constant)
extern const char* const kSyntaxErrorOnLine9;
extern const char* const kNanOnHalfHemisphere;

// {"environment": furnace hidden, one sphere with `brdf` and `params`, render WxH, max spp}.
nlohmann::json furnaceScene(const std::string& brdf, const nlohmann::json& params, int size, int maxSamples,
                            int samplesPerFrame = 8);

}  // namespace brdfa::itest
