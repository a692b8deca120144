// Test harness for the integration suite: a fixture sharing one real server per suite, and
// helpers for requests, images and scenes.
#pragma once

#include <gtest/gtest.h>
#include <httplib.h>

#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "server_process.h"

namespace brdfa::itest {

// True in the AddressSanitizer build (`make sanitize`), where the server's own code runs 2-3x
// slower: tests that bound a time scale it there, since that build checks memory, not seconds.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitizedBuild = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitizedBuild = true;
#else
inline constexpr bool kSanitizedBuild = false;
#endif
#else
inline constexpr bool kSanitizedBuild = false;
#endif

// The server process itself lives in tests/support (the bench uses it too); this wrapper
// starts the binary under test from the source tree.
class ServerProcess : public testsupport::ServerProcess {
 public:
  std::string start(const std::vector<std::string>& extraArgs = {}) {
    return testsupport::ServerProcess::start(BRDFA_SERVER_BINARY, BRDFA_SOURCE_DIR, extraArgs);
  }
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
  // POST /api/sessions with `scene`; the new session's id ("" after a failed expectation).
  static std::string createSession(const nlohmann::json& scene);
  // Polls GET /api/jobs/{id} until it is no longer queued or running, expecting progress in
  // [0, 1] that never goes back; the last answer (a failed expectation on timeout).
  static nlohmann::json waitForJob(const std::string& id, std::chrono::seconds timeout);
  // Expects an error answer: `status` with a JSON {error, message} body naming `field`.
  static void expectError(const httplib::Result& r, int status, const std::string& field);

  static std::unique_ptr<ServerProcess> server_;
  static std::string startError_;
};

// Parses a response body as JSON (null when it is not JSON).
nlohmann::json bodyJson(const httplib::Result& r);

// A file of the source tree, by its path relative to the repository root ("" when unreadable).
std::string readRepoFile(const std::string& relative);

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
extern const char* const kLambertWhite;     // color Kd 1 1 1, f = Kd / pi (own PI constant)
extern const char* const kTexturedLambert;  // f = Kd * texture(iTexture0, texCoord).rgb / pi
extern const char* const kSyntaxErrorOnLine9;
extern const char* const kNanOnHalfHemisphere;

// {"environment": furnace hidden, one sphere with `brdf` and `params`, render WxH, max spp}.
nlohmann::json furnaceScene(const std::string& brdf, const nlohmann::json& params, int size, int maxSamples,
                            int samplesPerFrame = 8);

// Raw sockets, for clients httplib's cannot be (trickling a request, hanging up mid-render).
// A blocking TCP connection to the server on loopback, from `source` (another loopback address
// is another client address); -1 on failure.
int connectTo(int port, const char* source = "127.0.0.1");
bool sendAll(int fd, const std::string& bytes);
// True once the server closed (or reset) the connection; reads and drops what it sent first.
bool closedByServer(int fd);

}  // namespace brdfa::itest
