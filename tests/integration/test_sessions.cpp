// Interactive sessions: scenes, frames with min_spp, stats, the multipart PNG stream, isolation.
#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <optional>
#include <thread>

#include <stb/stb_image.h>  // a system header: its unused static functions raise no warnings

#include "brdfa/image_codec.h"
#include "server_fixture.h"

namespace brdfa::itest {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

class Sessions : public ServerTest {
 protected:
  void SetUp() override {
    ServerTest::SetUp();
    // Our own white Lambertian: the test knows its parameter names, whatever the built-ins are.
    auto r = put("/api/brdfs/itest_lambert", kLambertWhite, "text/plain");
    ASSERT_TRUE(r);
    ASSERT_TRUE(r->status == 200 || r->status == 201) << r->body;
  }

  // GET frame as PFM, asserting 200; returns the image and X-Samples.
  static void frame(const std::string& session, uint64_t minSpp, Image& img, uint64_t* samples = nullptr) {
    auto r = get("/api/sessions/" + session + "/frame?format=pfm&min_spp=" + std::to_string(minSpp));
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    ASSERT_TRUE(r->has_header("X-Samples"));
    ASSERT_TRUE(r->has_header("X-Render-Ms"));
    if (samples) *samples = std::stoull(r->get_header_value("X-Samples"));
    ASSERT_TRUE(decodeImage(r->body, img));
  }

  static double interiorMean(const Image& img, double expected, double tolerance) {
    auto interior = interiorPixels(img);
    EXPECT_GT(interior.size(), img.width * img.height / 5);
    double sum = 0;
    int bad = 0;
    for (auto [x, y] : interior) {
      double v = img.lum(x, y);
      if (std::fabs(v - expected) > tolerance) ++bad;
      sum += v;
    }
    EXPECT_EQ(bad, 0) << "interior pixels off by more than " << tolerance;
    return interior.empty() ? 0.0 : sum / interior.size();
  }
};

TEST_F(Sessions, DefaultSessionExistsWithTheDocumentedScene) {
  auto r = get("/api/sessions/default/scene");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  json scene = bodyJson(r);
  EXPECT_EQ(scene["environment"]["name"], "sky");
  EXPECT_EQ(scene["environment"]["visible"], true);
  ASSERT_EQ(scene["objects"].size(), 1u);
  EXPECT_EQ(scene["objects"][0]["mesh"], "sphere");
  EXPECT_EQ(scene["objects"][0]["brdf"], "ggx");
  EXPECT_EQ(scene["render"]["width"], 512);
  EXPECT_EQ(scene["render"]["height"], 512);
  EXPECT_EQ(scene["render"]["samples_per_frame"], 4);
  EXPECT_EQ(scene["render"]["max_samples"], 4096);
  // Round trip: what GET returns, PUT accepts unchanged, and GET then returns the same.
  auto p = put("/api/sessions/default/scene", r->body);
  ASSERT_TRUE(p);
  ASSERT_EQ(p->status, 200) << p->body;
  EXPECT_EQ(bodyJson(p), scene);
  EXPECT_EQ(bodyJson(get("/api/sessions/default/scene")), scene);
}

TEST_F(Sessions, FrameStatsAndParameterOnlyPatch) {
  json scene = furnaceScene("itest_lambert", {{"Kd", {1, 1, 1}}}, 64, 64);
  auto r = put("/api/sessions/default/scene", scene.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  json full = bodyJson(r);
  EXPECT_EQ(full["render"]["width"], 64);
  EXPECT_EQ(full["camera"]["fov"], 45);  // defaults filled in

  Image img;
  uint64_t samples = 0;
  ASSERT_NO_FATAL_FAILURE(frame("default", 64, img, &samples));
  EXPECT_GE(samples, 64u);
  EXPECT_EQ(img.width, 64);
  EXPECT_NEAR(interiorMean(img, 1.0, 0.01), 1.0, 0.002);

  json stats = bodyJson(get("/api/sessions/default/stats"));
  EXPECT_EQ(stats["spp"], 64) << stats.dump();
  // Done by max_samples; "converged" is reserved for render.target_error (none here).
  EXPECT_EQ(stats["max_samples_reached"], true) << stats.dump();
  EXPECT_EQ(stats["done"], true) << stats.dump();
  EXPECT_EQ(stats["converged"], false) << stats.dump();
  for (const char* key : {"elapsed_ms", "ms_per_frame", "fps", "vertices", "triangles", "rel_error", "nan_samples",
                          "passes", "scene_version"})
    EXPECT_TRUE(stats.contains(key)) << key;
  EXPECT_GT(stats["vertices"].get<int>(), 0);
  EXPECT_EQ(stats["nan_samples"], 0);
  uint64_t version = stats["scene_version"].get<uint64_t>();

  // Parameter-only merge patch: Kd to 0.5 (objects is an array: sent whole, RFC 7386).
  json patchBody = {{"objects", json::array({{{"brdf", "itest_lambert"}, {"params", {{"Kd", {0.5, 0.5, 0.5}}}}}})}};
  r = patch("/api/sessions/default/scene", patchBody.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(bodyJson(r)["render"]["width"], 64) << "PATCH must keep what it does not mention";
  ASSERT_NO_FATAL_FAILURE(frame("default", 64, img, &samples));
  EXPECT_GE(samples, 64u);
  EXPECT_NEAR(interiorMean(img, 0.5, 0.005), 0.5, 0.001);
  stats = bodyJson(get("/api/sessions/default/stats"));
  EXPECT_GT(stats["scene_version"].get<uint64_t>(), version);

  // A camera-only patch keeps the objects.
  r = patch("/api/sessions/default/scene", R"({"camera": {"fov": 40}})");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  json after = bodyJson(r);
  EXPECT_EQ(after["camera"]["fov"], 40);
  EXPECT_EQ(after["objects"][0]["params"]["Kd"], json({0.5, 0.5, 0.5}));
}

TEST_F(Sessions, MinSppBeyondMaxSamplesDoesNotHang) {
  auto r = put("/api/sessions/default/scene", furnaceScene("itest_lambert", json::object(), 32, 16, 4).dump());
  ASSERT_TRUE(r && r->status == 200);
  auto t0 = Clock::now();
  r = get("/api/sessions/default/frame?format=png&min_spp=99999999999999999999999");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(r->get_header_value("X-Samples"), "16");
  EXPECT_EQ(r->body.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_LT(Clock::now() - t0, std::chrono::seconds(20));
}

// Reads multipart/x-mixed-replace parts from the stream, checking the framing of each: the
// boundary, a Content-Type: image/png header, a PNG body ending at CRLF + the next boundary
// (which, with the next part's headers, the server sends right after each frame). The sample
// count of each part comes from its PNG's tEXt chunk "brdfa:spp".
struct PartReader {
  std::string buf;
  std::vector<std::string> pngs;
  std::vector<uint64_t> samples;
  std::string error;

  // Returns false when the data cannot be multipart framing (then `error` says why).
  bool parse() {
    static const std::string kHeaders = "--frame\r\nContent-Type: image/png\r\n\r\n";
    static const std::string kEnd = "\r\n--frame\r\n";
    for (;;) {
      if (buf.size() < kHeaders.size()) return true;
      if (buf.compare(0, kHeaders.size(), kHeaders) != 0) {
        error = "part does not start with the boundary and its headers: " + buf.substr(0, 40);
        return false;
      }
      size_t end = buf.find(kEnd, kHeaders.size());
      if (end == std::string::npos) return true;  // need more bytes
      std::string png = buf.substr(kHeaders.size(), end - kHeaders.size());
      if (png.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) != 0) {
        error = "part body is not a PNG";
        return false;
      }
      std::string spp = pngText(std::vector<uint8_t>(png.begin(), png.end()), "brdfa:spp");
      if (spp.empty()) {
        error = "part PNG without its brdfa:spp text";
        return false;
      }
      pngs.push_back(std::move(png));
      samples.push_back(std::stoull(spp));
      buf.erase(0, end + 2);  // keep the boundary: it starts the next part
    }
  }
};

TEST_F(Sessions, StreamDeliversMultipartPngParts) {
  // Never converges within the test: frames keep coming.
  auto r = put("/api/sessions/default/scene", furnaceScene("itest_lambert", json::object(), 32, 1 << 20, 1).dump());
  ASSERT_TRUE(r && r->status == 200);
  auto cli = server_->client(20);
  PartReader reader;
  std::string contentType;
  bool framingOk = true;
  auto res = cli->Get(
      "/api/sessions/default/stream", httplib::Headers{},
      [&](const httplib::Response& response) {
        contentType = response.get_header_value("Content-Type");
        return response.status == 200;
      },
      [&](const char* data, size_t len) {
        reader.buf.append(data, len);
        framingOk = reader.parse();
        return framingOk && reader.pngs.size() < 3;  // stop after 3 parts
      });
  (void)res;  // canceled by us: not an error here
  EXPECT_EQ(contentType, "multipart/x-mixed-replace; boundary=frame");
  ASSERT_TRUE(framingOk) << reader.error;
  ASSERT_GE(reader.pngs.size(), 2u);
  for (const std::string& png : reader.pngs) EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  // Only newer frames are sent: more samples, or the same count with more of a pass shown (a
  // slow pass, as under the sanitizers, is shown partway at the stream's frame interval).
  EXPECT_TRUE(reader.samples[1] > reader.samples[0] ||
              (reader.samples[1] == reader.samples[0] && reader.pngs[1] != reader.pngs[0]))
      << "samples " << reader.samples[0] << " then " << reader.samples[1]
      << ", the same image: " << (reader.pngs[1] == reader.pngs[0]);

  // After a scene change a new client gets only frames of the new scene (the old one had far
  // more than 8 spp), ending promptly with the converged frame (Kd changes, so accumulation
  // restarts; passes ramp 1, 2, 4, 1 samples up to max_samples 8).
  r = put("/api/sessions/default/scene", furnaceScene("itest_lambert", {{"Kd", {0.5, 0.5, 0.5}}}, 32, 8, 8).dump());
  ASSERT_TRUE(r && r->status == 200);
  PartReader second;
  auto t0 = Clock::now();
  cli->Get("/api/sessions/default/stream", httplib::Headers{}, [&](const char* data, size_t len) {
    second.buf.append(data, len);
    return second.parse() && (second.samples.empty() || second.samples.back() < 8u);
  });
  ASSERT_FALSE(second.pngs.empty()) << second.error;
  EXPECT_LT(Clock::now() - t0, std::chrono::seconds(5));
  for (uint64_t spp : second.samples) EXPECT_LE(spp, 8u) << "a frame of the previous scene";
  EXPECT_EQ(second.samples.back(), 8u);
}

// Width in the IHDR chunk of a PNG (bytes 16..19, big-endian); 0 when too short.
uint32_t pngWidth(const std::string& png) {
  if (png.size() < 24) return 0;
  uint32_t w = 0;
  for (int i = 16; i < 20; ++i) w = (w << 8) | static_cast<unsigned char>(png[i]);
  return w;
}

// Reads the default session's stream from its start until the part with `lastSpp` samples.
PartReader streamUntil(ServerProcess& server, uint64_t lastSpp) {
  auto cli = server.client(20);
  PartReader reader;
  cli->Get("/api/sessions/default/stream", httplib::Headers{}, [&](const char* data, size_t len) {
    reader.buf.append(data, len);
    return reader.parse() && (reader.samples.empty() || reader.samples.back() < lastSpp);
  });
  return reader;
}

TEST_F(Sessions, StreamSendsHalfSizePreviewsUntilFourSamplesAndTheConvergedFrameFullSize) {
  // 512x512, passes ramp 1, 2, 4, 4, 4, 1 samples up to 16.
  auto r = put("/api/sessions/default/scene", furnaceScene("itest_lambert", json::object(), 512, 16, 4).dump());
  ASSERT_TRUE(r && r->status == 200);
  PartReader reader = streamUntil(*server_, 16);
  ASSERT_TRUE(reader.error.empty()) << reader.error;
  ASSERT_FALSE(reader.pngs.empty());
  EXPECT_EQ(reader.samples.back(), 16u);
  bool sawPreview = false;
  for (size_t i = 0; i < reader.pngs.size(); ++i) {
    const bool preview = reader.samples[i] < 4;
    sawPreview = sawPreview || preview;
    EXPECT_EQ(pngWidth(reader.pngs[i]), preview ? 256u : 512u) << "part " << i << " at " << reader.samples[i] << " spp";
  }
  // A client that connects at once gets the first pass (1 spp) as its first part.
  if (reader.samples.front() == 1) {
    EXPECT_TRUE(sawPreview);
  }

  // With max_samples 2 the converged frame has 2 samples and still comes full size.
  r = put("/api/sessions/default/scene", furnaceScene("itest_lambert", {{"Kd", {0.5, 0.5, 0.5}}}, 512, 2, 4).dump());
  ASSERT_TRUE(r && r->status == 200);
  PartReader converged = streamUntil(*server_, 2);
  ASSERT_FALSE(converged.pngs.empty()) << converged.error;
  EXPECT_EQ(converged.samples.back(), 2u);
  EXPECT_EQ(pngWidth(converged.pngs.back()), 512u);

  // Small frames are never halved: a 128x128 first pass comes at 128.
  r = put("/api/sessions/default/scene", furnaceScene("itest_lambert", json::object(), 128, 1, 1).dump());
  ASSERT_TRUE(r && r->status == 200);
  PartReader small = streamUntil(*server_, 1);
  ASSERT_FALSE(small.pngs.empty()) << small.error;
  EXPECT_EQ(pngWidth(small.pngs.back()), 128u);

  // The frame endpoint always answers full size.
  r = put("/api/sessions/default/scene", furnaceScene("itest_lambert", json::object(), 512, 64, 1).dump());
  ASSERT_TRUE(r && r->status == 200);
  r = get("/api/sessions/default/frame?format=png&min_spp=1");
  ASSERT_TRUE(r && r->status == 200);
  EXPECT_EQ(pngWidth(r->body), 512u);
}

// The RGB codes of a PNG body's central 32x32 pixels, and its width (0: not a PNG).
std::vector<std::array<int, 3>> pngCentreBlock(const std::string& body, int& width) {
  int h = 0, n = 0;
  width = 0;
  stbi_uc* px =
      stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(body.data()), int(body.size()), &width, &h, &n, 4);
  if (!px) return {};
  std::vector<std::array<int, 3>> block;
  for (int y = h / 2 - 16; y < h / 2 + 16; ++y)
    for (int x = width / 2 - 16; x < width / 2 + 16; ++x) {
      const stbi_uc* c = px + (size_t(y) * width + x) * 4;
      block.push_back({c[0], c[1], c[2]});
    }
  stbi_image_free(px);
  return block;
}

// A new program's first frame, as the stream shows it, is also what GET /frame?min_spp=1
// answers at once (the session's last read, while the program's first pass is still to come or
// in flight), full size where the stream's part is a half-size preview; and it is the furnace's
// exact 1 (clamp tone map: code 255). A display change (exposure -1 stop: 0.5, sRGB code 188)
// is never answered from that read.
TEST_F(Sessions, AReadAfterTheStreamsFirstFrameGetsThatImageFullSizeAndNeverAStaleOne) {
  std::string text = kLambertWhite;
  text.insert(text.find("::end shader"), "// first frame " + std::to_string(::getpid()) + "\n");  // a new program
  auto r = put("/api/brdfs/itest_first_frame", text, "text/plain");
  ASSERT_TRUE(r && (r->status == 200 || r->status == 201)) << (r ? r->body : "");
  json scene = furnaceScene("itest_first_frame", json::object(), 512, 64, 4);
  r = put("/api/sessions/default/scene", scene.dump());
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  const uint64_t version = bodyJson(get("/api/sessions/default/stats"))["scene_version"].get<uint64_t>();
  PartReader reader = streamUntil(*server_, 1);
  ASSERT_FALSE(reader.pngs.empty()) << reader.error;

  r = get("/api/sessions/default/frame?format=png&min_spp=1");
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  EXPECT_EQ(std::stoull(r->get_header_value("X-Scene-Version")), version);
  EXPECT_GE(std::stoull(r->get_header_value("X-Samples")), 1u);
  int width = 0;
  for (const auto& rgb : pngCentreBlock(r->body, width)) ASSERT_EQ(rgb, (std::array<int, 3>{255, 255, 255}));
  EXPECT_EQ(width, 512);

  scene["render"]["exposure"] = -1;
  r = put("/api/sessions/default/scene", scene.dump());
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  r = get("/api/sessions/default/frame?format=png&min_spp=1");
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  EXPECT_GT(std::stoull(r->get_header_value("X-Scene-Version")), version);
  const auto block = pngCentreBlock(r->body, width);
  ASSERT_FALSE(block.empty());
  for (const auto& rgb : block)
    for (int c : rgb) ASSERT_NEAR(c, 188, 1) << "0.5 in sRGB: 187.5";
}

// A script that reads a new program's first frame and moves on: the first sample stands for
// Session::kFirstPassGrace (80 ms) unless a reader asks for more, so the next change does not
// wait for the driver's compile of a program it has left, and that program never runs. On a
// CPU device (the only kind with first samples), when the change came within the grace, going
// back to the program starts with a first sample again: its own kernel has not run; and that
// first sample is the furnace's exact 1. A read of 8 samples then ends the wait, and the
// program's passes replace the first sample (spp counts from them: 8 exactly, max_samples 8),
// exactly 1 in the furnace.
TEST_F(Sessions, AFirstSampleStandsBrieflyUnlessAReaderWantsMore) {
  const bool cpu = bodyJson(get("/api/health"))["device"]["type"] == "cpu";
  std::string text = kLambertWhite;
  text.insert(text.find("::end shader"), "// grace " + std::to_string(::getpid()) + "\n");  // a new program
  auto r = put("/api/brdfs/itest_grace", text, "text/plain");
  ASSERT_TRUE(r && (r->status == 200 || r->status == 201)) << (r ? r->body : "");
  const std::string fresh = furnaceScene("itest_grace", json::object(), 256, 8, 4).dump();
  const std::string known = furnaceScene("itest_lambert", json::object(), 256, 8, 4).dump();
  Image img;
  uint64_t samples = 0;
  r = put("/api/sessions/default/scene", known);  // its program built and run
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  ASSERT_NO_FATAL_FAILURE(frame("default", 8, img));

  // The first sample is there at some moment after the last stats read that did not show it
  // began: a change made within 60 ms of that read's start is within the grace.
  r = put("/api/sessions/default/scene", fresh);
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  std::optional<Clock::time_point> before;  // the start of the last read without it
  for (int i = 0; i < 5000; ++i) {
    const auto t = Clock::now();
    if (bodyJson(get("/api/sessions/default/stats"))["spp"].get<uint64_t>() >= 1) break;
    before = t;
  }
  r = put("/api/sessions/default/scene", known);
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  const bool inGrace = before && Clock::now() - *before < std::chrono::milliseconds(60);

  r = put("/api/sessions/default/scene", fresh);
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  ASSERT_NO_FATAL_FAILURE(frame("default", 1, img, &samples));
  json stats = bodyJson(get("/api/sessions/default/stats"));
  if (cpu && inGrace) {
    EXPECT_EQ(samples, 1u);
    EXPECT_TRUE(stats["provisional"].get<bool>()) << "the program ran while its first sample stood: " << stats.dump();
  }
  EXPECT_NEAR(interiorMean(img, 1.0, 1e-4), 1.0, 1e-4);
  ASSERT_NO_FATAL_FAILURE(frame("default", 8, img, &samples));
  EXPECT_EQ(samples, 8u);
  EXPECT_NEAR(interiorMean(img, 1.0, 1e-4), 1.0, 1e-4);
  stats = bodyJson(get("/api/sessions/default/stats"));
  EXPECT_FALSE(stats["provisional"].get<bool>()) << stats.dump();
  EXPECT_TRUE(stats["done"].get<bool>()) << stats.dump();
}

// While a stream client watches, each pass is sized to a 42 ms frame (Session::kStreamFrameMs);
// a script waiting on /frame gets passes of samples_per_frame. Up to 511 samples with 256 per
// pass, the unwatched passes ramp 1, 2, ... 256: 9 of them. The BRDF is a white Lambertian
// made slow (tests/hostile/slow_loop.brdf, 40 rounds a sample), so that on lavapipe a pass of
// one sample fits a frame and one of 256 does not: watched, the passes are smaller and more.
// It is 1 in the furnace whatever the pass sizes.
TEST_F(Sessions, AWatchedStreamTakesPassesThatFitItsFrameInterval) {
  auto r = put("/api/brdfs/itest_slow_lambert", readRepoFile("tests/hostile/slow_loop.brdf"), "text/plain");
  ASSERT_TRUE(r && (r->status == 200 || r->status == 201)) << (r ? r->body : "");
  auto scene = [](double iterations) {
    return furnaceScene("itest_slow_lambert", {{"iterations", iterations}}, 512, 511, 256).dump();
  };
  r = put("/api/sessions/default/scene", scene(40));
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  Image img;
  ASSERT_NO_FATAL_FAILURE(frame("default", 511, img));
  json unwatched = bodyJson(get("/api/sessions/default/stats"));
  EXPECT_EQ(unwatched["passes"], 9) << unwatched.dump();
  EXPECT_NEAR(interiorMean(img, 1.0, 1e-4), 1.0, 1e-4);
  const double fullPassMs = unwatched["last_pass_ms"].get<double>();
  constexpr double kStreamFrameMs = 42;  // Session::kStreamFrameMs
  if (fullPassMs < 4 * kStreamFrameMs)
    GTEST_SKIP() << "a 256-sample pass took " << fullPassMs << " ms on this device: passes of a frame would be large";

  r = put("/api/sessions/default/scene", scene(41));  // a restart: the passes are measured afresh
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  PartReader reader = streamUntil(*server_, 511);
  ASSERT_TRUE(reader.error.empty()) << reader.error;
  EXPECT_EQ(reader.samples.back(), 511u);
  json watched = bodyJson(get("/api/sessions/default/stats"));
  // The AddressSanitizer build reads a frame several times slower, which leaves a pass too
  // little of the frame: out of reach, passes rightly keep their size there.
  if (!kSanitizedBuild) {
    EXPECT_GT(watched["passes"].get<int>(), 12) << "a 256-sample pass took " << fullPassMs << " ms; " << watched.dump();
  }
  ASSERT_NO_FATAL_FAILURE(frame("default", 511, img));
  EXPECT_NEAR(interiorMean(img, 1.0, 1e-4), 1.0, 1e-4);
}

TEST_F(Sessions, TwoSessionsKeepSeparateScenes) {
  auto ra = post("/api/sessions", furnaceScene("itest_lambert", {{"Kd", {0.25, 0.25, 0.25}}}, 32, 16).dump());
  auto rb = post("/api/sessions", furnaceScene("itest_lambert", {{"Kd", {0.75, 0.75, 0.75}}}, 48, 16).dump());
  ASSERT_TRUE(ra && rb);
  ASSERT_EQ(ra->status, 201) << ra->body;
  ASSERT_EQ(rb->status, 201) << rb->body;
  std::string a = bodyJson(ra)["id"], b = bodyJson(rb)["id"];
  ASSERT_NE(a, b);

  Image ia, ib;
  ASSERT_NO_FATAL_FAILURE(frame(a, 16, ia));
  ASSERT_NO_FATAL_FAILURE(frame(b, 16, ib));
  EXPECT_EQ(ia.width, 32);
  EXPECT_EQ(ib.width, 48);
  EXPECT_NEAR(interiorMean(ia, 0.25, 0.003), 0.25, 0.001);
  EXPECT_NEAR(interiorMean(ib, 0.75, 0.008), 0.75, 0.002);

  // Changing A leaves B alone.
  auto r = patch(
      "/api/sessions/" + a + "/scene",
      json{{"objects", json::array({{{"brdf", "itest_lambert"}, {"params", {{"Kd", {0.9, 0.9, 0.9}}}}}})}}.dump());
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  ASSERT_NO_FATAL_FAILURE(frame(a, 16, ia));
  ASSERT_NO_FATAL_FAILURE(frame(b, 16, ib));
  EXPECT_NEAR(interiorMean(ia, 0.9, 0.01), 0.9, 0.002);
  EXPECT_NEAR(interiorMean(ib, 0.75, 0.008), 0.75, 0.002);
  EXPECT_EQ(bodyJson(get("/api/sessions/" + b + "/scene"))["objects"][0]["params"]["Kd"], json({0.75, 0.75, 0.75}));

  auto list = bodyJson(get("/api/sessions"));
  EXPECT_GE(list.size(), 3u);

  // Deleting ends them; default stays.
  for (const std::string& id : {a, b}) {
    auto d = del("/api/sessions/" + id);
    ASSERT_TRUE(d);
    EXPECT_EQ(d->status, 204);
    auto g = get("/api/sessions/" + id);
    ASSERT_TRUE(g);
    EXPECT_EQ(g->status, 404);
  }
  auto g = get("/api/sessions/default");
  ASSERT_TRUE(g);
  EXPECT_EQ(g->status, 200);
}

TEST_F(Sessions, DeletingASessionEndsItsStreams) {
  auto r = post("/api/sessions", furnaceScene("itest_lambert", json::object(), 32, 1 << 20, 1).dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  std::string id = bodyJson(r)["id"];
  std::atomic<size_t> received{0};
  std::atomic<bool> ended{false};
  std::thread streamer([&] {
    auto cli = server_->client(30);
    cli->Get("/api/sessions/" + id + "/stream", httplib::Headers{}, [&](const char*, size_t len) {
      received += len;
      return true;
    });
    ended = true;
  });
  for (auto deadline = Clock::now() + std::chrono::seconds(10); received == 0 && Clock::now() < deadline;)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_GT(received.load(), 0u);
  auto d = del("/api/sessions/" + id);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->status, 204);
  for (auto deadline = Clock::now() + std::chrono::seconds(5); !ended && Clock::now() < deadline;)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_TRUE(ended.load()) << "stream still open after its session was deleted";
  streamer.join();
}

TEST_F(Sessions, SessionCountIsCapped) {
  std::vector<std::string> ids;
  int status = 0;
  for (int i = 0; i < 40; ++i) {
    auto r = post("/api/sessions", furnaceScene("itest_lambert", json::object(), 16, 1).dump());
    ASSERT_TRUE(r);
    status = r->status;
    if (status != 201) break;
    ids.push_back(bodyJson(r)["id"]);
  }
  EXPECT_EQ(status, 429);
  EXPECT_EQ(bodyJson(get("/api/sessions")).size(), ids.size() + 1);  // + default
  for (const std::string& id : ids) EXPECT_EQ(del("/api/sessions/" + id)->status, 204);
  auto r = post("/api/sessions", "");  // room again; an empty body takes every default
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  json scene = bodyJson(r)["scene"];
  EXPECT_EQ(scene["environment"]["name"], "furnace");
  EXPECT_EQ(scene["objects"][0]["brdf"], "lambert");
  EXPECT_EQ(del("/api/sessions/" + bodyJson(r)["id"].get<std::string>())->status, 204);
}

// Browser tabs create sessions and cannot reliably delete them. At the cap, a new session
// reclaims the one unused for longest, once it has been unused for --session-reclaim seconds;
// a session whose stats are polled (an open tab) is never taken, nor is `default`.
TEST(SessionReclaim, AtTheCapTheLongestUnusedSessionMakesRoom) {
  ServerProcess server;
  ASSERT_EQ(server.start({"--session-reclaim", "2"}), "");
  auto client = server.client();
  const std::string scene = furnaceScene("lambert", json::object(), 16, 1).dump();
  std::vector<std::string> ids;
  for (int i = 0; i < 40; ++i) {
    auto r = client->Post("/api/sessions", scene, "application/json");
    ASSERT_TRUE(r);
    if (r->status != 201) {
      EXPECT_EQ(r->status, 429) << "nothing is old enough to reclaim yet";
      break;
    }
    ids.push_back(bodyJson(r)["id"]);
  }
  ASSERT_GE(ids.size(), 2u);
  // ids[0] stays in use (an open tab polls its stats); the others are abandoned.
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(client->Get("/api/sessions/" + ids[0] + "/stats")->status, 200);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  auto r = client->Post("/api/sessions", scene, "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  EXPECT_EQ(client->Get("/api/sessions/" + ids[0])->status, 200) << "a session in use is never reclaimed";
  EXPECT_EQ(client->Get("/api/sessions/default")->status, 200);
  int gone = 0;
  for (size_t i = 1; i < ids.size(); ++i) gone += client->Get("/api/sessions/" + ids[i])->status == 404 ? 1 : 0;
  EXPECT_EQ(gone, 1) << "exactly one abandoned session made room";
  EXPECT_EQ(server.terminate(), 0);
}

TEST_F(Sessions, NanProducingBrdfIsCountedAndNeverReachesPixels) {
  auto r = put("/api/brdfs/itest_nan", kNanOnHalfHemisphere, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_TRUE(r->status == 200 || r->status == 201) << r->body;
  r = post("/api/sessions", furnaceScene("itest_nan", json::object(), 32, 64).dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  std::string id = bodyJson(r)["id"];
  Image img;
  uint64_t samples = 0;
  ASSERT_NO_FATAL_FAILURE(frame(id, 64, img, &samples));
  EXPECT_GE(samples, 64u);
  size_t nonFinite = 0;
  for (float v : img.rgba) nonFinite += !std::isfinite(v);
  EXPECT_EQ(nonFinite, 0u) << "NaN/Inf samples must be dropped, not accumulated";
  json stats = bodyJson(get("/api/sessions/" + id + "/stats"));
  EXPECT_GT(stats["nan_samples"].get<uint64_t>(), 0u) << stats.dump();
  // The PNG of the same session decodes fine too.
  auto png = get("/api/sessions/" + id + "/frame");
  ASSERT_TRUE(png);
  EXPECT_EQ(png->status, 200);
  del("/api/sessions/" + id);

  // The one-shot render reports the count in a header.
  json body = furnaceScene("itest_nan", json::object(), 32, 16);
  body["spp"] = 16;
  body["format"] = "pfm";
  r = post("/api/render", body.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_GT(std::stoull(r->get_header_value("X-Nan-Samples")), 0u);
  ASSERT_TRUE(decodeImage(r->body, img));
  for (float v : img.rgba) ASSERT_TRUE(std::isfinite(v));
}

// Values carried from one BRDF to another by name (the UI keeps them) that
// fall outside the new BRDF's range are clamped, the scene says so, and nothing renders NaN.
TEST_F(Sessions, ParameterValuesOutsideTheBrdfsRangeAreClampedAndTheSceneSaysSo) {
  // Disney's roughness 0 carried into ggx (minimum 0.001), and a colour past 0..1.
  json scene = furnaceScene("ggx", {{"roughness", 0.0}, {"F0", {1.5, -0.25, 0.5}}}, 32, 16);
  auto created = post("/api/sessions", scene.dump());
  ASSERT_TRUE(created);
  ASSERT_EQ(created->status, 201) << created->body;
  const std::string id = bodyJson(created).value("id", "");
  const json answered = bodyJson(created)["scene"];
  const json& params = answered["objects"][0]["params"];
  EXPECT_FLOAT_EQ(params.value("roughness", -1.0f), 0.001f) << answered.dump();
  EXPECT_EQ(params["F0"], json({1.0, 0.0, 0.5})) << answered.dump();
  ASSERT_TRUE(answered.contains("notes")) << answered.dump();
  const std::string notes = answered["notes"].dump();
  EXPECT_NE(notes.find("objects[0].params.roughness: 0 is outside ggx's range 0.001..1; clamped to 0.001"),
            std::string::npos)
      << notes;
  EXPECT_NE(notes.find("objects[0].params.F0"), std::string::npos) << notes;

  // The scene's GET says so too, and a GET scene PUT back is accepted (its notes ignored, and
  // gone: nothing is out of range any more).
  auto got = get("/api/sessions/" + id + "/scene");
  ASSERT_TRUE(got && got->status == 200);
  const json fetched = bodyJson(got);
  EXPECT_EQ(fetched["notes"], answered["notes"]);
  auto back = put("/api/sessions/" + id + "/scene", fetched.dump());
  ASSERT_TRUE(back);
  ASSERT_EQ(back->status, 200) << back->body;
  EXPECT_FALSE(bodyJson(back).contains("notes")) << back->body;

  // Rendered with the clamped values: no NaN sample, finite pixels.
  auto frame = get("/api/sessions/" + id + "/frame?min_spp=16&format=pfm");
  ASSERT_TRUE(frame && frame->status == 200);
  Image img;
  ASSERT_TRUE(decodeImage(frame->body, img));
  for (float v : img.rgba) ASSERT_TRUE(std::isfinite(v));
  auto stats = get("/api/sessions/" + id + "/stats");
  ASSERT_TRUE(stats && stats->status == 200);
  EXPECT_EQ(bodyJson(stats).value("nan_samples", uint64_t(1)), 0u) << stats->body;

  // A PATCH that switches the BRDF and carries the value again is clamped again.
  auto patched = patch("/api/sessions/" + id + "/scene",
                       json{{"objects", {{{"brdf", "ggx"}, {"params", {{"roughness", -3.0}}}}}}}.dump());
  ASSERT_TRUE(patched && patched->status == 200) << (patched ? patched->body : "");
  EXPECT_FLOAT_EQ(bodyJson(patched)["objects"][0]["params"].value("roughness", -1.0f), 0.001f);
  EXPECT_TRUE(bodyJson(patched).contains("notes"));
  del("/api/sessions/" + id);
}

}  // namespace
}  // namespace brdfa::itest
