// The frame saver: PNG, PFM and EXR frames from sessions and one-shot renders, their
// Content-Disposition, and the tone maps of the PNG display image, checked on the white
// furnace whose exact radiance is 1.
#include <tinyexr.h>  // Debian's shared libtinyexr (no TINYEXR_IMPLEMENTATION)

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>

#include "server_fixture.h"

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_PNG
#include <stb/stb_image.h>  // a system header: its unused static functions raise no warnings

namespace brdfa::itest {
namespace {

using nlohmann::json;

// RGBA floats of an EXR body, row 0 at the top; empty when tinyexr refuses it.
std::vector<float> decodeExr(const std::string& body, int& width, int& height) {
  float* rgba = nullptr;
  const char* err = nullptr;
  std::vector<float> out;
  if (LoadEXRFromMemory(&rgba, &width, &height, reinterpret_cast<const unsigned char*>(body.data()), body.size(),
                        &err) != TINYEXR_SUCCESS) {
    ADD_FAILURE() << "tinyexr: " << (err ? err : "?");
    if (err) FreeEXRErrorMessage(err);
    return out;
  }
  out.assign(rgba, rgba + size_t(width) * height * 4);
  std::free(rgba);
  return out;
}

// The centre pixel's RGB of a PNG body.
std::array<int, 3> pngCentre(const std::string& body) {
  int w = 0, h = 0, n = 0;
  stbi_uc* px = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(body.data()), int(body.size()), &w, &h, &n, 4);
  if (!px) {
    ADD_FAILURE() << "not a PNG: " << stbi_failure_reason();
    return {-1, -1, -1};
  }
  const stbi_uc* c = px + (size_t(h / 2) * w + w / 2) * 4;
  std::array<int, 3> rgb{c[0], c[1], c[2]};
  stbi_image_free(px);
  return rgb;
}

// sRGB code of a linear value in [0, 1] (IEC 61966-2-1, rounded to nearest).
int srgbCode(double linear) {
  double e = linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
  return static_cast<int>(std::floor(e * 255.0 + 0.5));
}

// Narkowicz 2015 ACES fit, as the brief and shaders/lib/tonemap.glsl state it.
double acesFit(double x) { return std::clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0); }

json whiteFurnace(const std::string& tonemap, double exposure) {
  json scene = furnaceScene("lambert", {{"Kd", {1, 1, 1}}}, 32, 4, 4);
  scene["render"]["tonemap"] = tonemap;
  scene["render"]["exposure"] = exposure;
  return scene;
}

class FrameSaver : public ServerTest {
 protected:
  // A session with `scene`; its id.
  static std::string newSession(const json& scene) {
    auto r = post("/api/sessions", scene.dump());
    EXPECT_TRUE(r && r->status == 201) << (r ? r->body : "no response");
    return r ? bodyJson(r).value("id", "") : "";
  }
};

TEST_F(FrameSaver, SessionExrHoldsThePfmFloats) {
  json scene = {{"environment", {{"name", "sky"}, {"visible", true}}},
                {"objects", json::array({{{"mesh", "sphere"}, {"brdf", "ggx"}}})},
                {"render",
                 {{"width", 40},
                  {"height", 24},
                  {"max_samples", 8},
                  {"samples_per_frame", 4},
                  {"exposure", 3},
                  {"tonemap", "aces"}}}};
  const std::string id = newSession(scene);
  ASSERT_FALSE(id.empty());
  auto pfm = get("/api/sessions/" + id + "/frame?format=pfm&min_spp=8");
  auto exr = get("/api/sessions/" + id + "/frame?format=exr&min_spp=8");
  ASSERT_TRUE(pfm && exr);
  ASSERT_EQ(pfm->status, 200) << pfm->body;
  ASSERT_EQ(exr->status, 200) << exr->body;
  EXPECT_EQ(exr->get_header_value("Content-Type"), "image/x-exr");
  EXPECT_EQ(pfm->get_header_value("X-Samples"), "8");
  EXPECT_EQ(exr->get_header_value("X-Samples"), "8");
  EXPECT_EQ(exr->get_header_value("Content-Disposition"), "inline; filename=\"" + id + "-8spp.exr\"");
  EXPECT_EQ(pfm->get_header_value("Content-Disposition"), "inline; filename=\"" + id + "-8spp.pfm\"");

  Image ref;
  ASSERT_TRUE(decodeImage(pfm->body, ref));
  int w = 0, h = 0;
  std::vector<float> rgba = decodeExr(exr->body, w, h);
  ASSERT_EQ(w, 40);
  ASSERT_EQ(h, 24);
  // Linear radiance, not tone mapped or exposed: bit for bit what PFM holds, same row order.
  bool aboveOne = false;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(rgba[(size_t(y) * w + x) * 4 + c], ref.at(x, y, c)) << x << "," << y << "," << c;
        aboveOne |= ref.at(x, y, c) > 1.0f;
      }
  EXPECT_TRUE(aboveOne) << "the sky should hold radiance above 1";
  EXPECT_EQ(del("/api/sessions/" + id)->status, 204);
}

TEST_F(FrameSaver, OneShotExrIsLinearRadiance) {
  json body = {{"scene", whiteFurnace("aces", 5)}, {"spp", 4}, {"format", "exr"}};
  auto r = post("/api/render", body.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/x-exr");
  EXPECT_EQ(r->get_header_value("Content-Disposition"), "inline; filename=\"render-4spp.exr\"");
  int w = 0, h = 0;
  std::vector<float> rgba = decodeExr(r->body, w, h);
  ASSERT_EQ(w, 32);
  ASSERT_EQ(h, 32);
  // The white furnace is exactly 1 on the sphere whatever the exposure and tone map.
  const float* centre = &rgba[(size_t(16) * w + 16) * 4];
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre[c], 1.0f, 1e-5f);
}

TEST_F(FrameSaver, ToneMapsOfTheWhiteFurnace) {
  struct Case {
    const char* tonemap;
    double exposure;
    int expected;
  };
  const Case cases[] = {
      {"clamp", 0, 255},
      {"reinhard", 0, srgbCode(0.5)},  // e / (1 + e) at e = 1
      {"aces", 0, srgbCode(acesFit(1.0))},
      {"clamp", -1, srgbCode(0.5)},
      {"reinhard", -1, srgbCode(0.5 / 1.5)},
      {"aces", 2, srgbCode(acesFit(4.0))},
  };
  EXPECT_EQ(srgbCode(0.5), 188);
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.tonemap) + " at exposure " + std::to_string(c.exposure));
    auto r = post("/api/render", json{{"scene", whiteFurnace(c.tonemap, c.exposure)}, {"spp", 4}}.dump());
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
    EXPECT_EQ(r->get_header_value("Content-Disposition"), "inline; filename=\"render-4spp.png\"");
    // Host and device resolves may round the last code differently.
    for (int v : pngCentre(r->body)) EXPECT_NEAR(v, c.expected, 1);
  }
}

TEST_F(FrameSaver, DownloadAndFormatErrors) {
  const std::string id = newSession(whiteFurnace("clamp", 0));
  ASSERT_FALSE(id.empty());
  auto png = get("/api/sessions/" + id + "/frame?min_spp=4&download=1");
  ASSERT_TRUE(png);
  ASSERT_EQ(png->status, 200) << png->body;
  EXPECT_EQ(png->get_header_value("Content-Disposition"), "attachment; filename=\"" + id + "-4spp.png\"");
  auto inlinePfm = get("/api/sessions/" + id + "/frame?format=pfm&min_spp=4&download=0");
  ASSERT_TRUE(inlinePfm);
  EXPECT_EQ(inlinePfm->get_header_value("Content-Disposition"), "inline; filename=\"" + id + "-4spp.pfm\"");
  auto oneShot =
      post("/api/render?download=1", json{{"scene", whiteFurnace("clamp", 0)}, {"spp", 2}, {"format", "pfm"}}.dump());
  ASSERT_TRUE(oneShot);
  EXPECT_EQ(oneShot->get_header_value("Content-Disposition"), "attachment; filename=\"render-2spp.pfm\"");

  for (const std::string& path :
       {"/api/sessions/" + id + "/frame?format=bmp", "/api/sessions/" + id + "/frame?download=yes"}) {
    auto r = get(path);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << path;
    json body = bodyJson(r);
    EXPECT_EQ(body.value("error", ""), "invalid_argument");
    EXPECT_EQ(body.value("field", ""), path.find("bmp") != std::string::npos ? "format" : "download");
  }
  json body = bodyJson(get("/api/sessions/" + id + "/frame?format=bmp"));
  EXPECT_NE(body.value("message", "").find("png, pfm or exr"), std::string::npos) << body.dump();
  auto badOneShot = post("/api/render", json{{"scene", whiteFurnace("clamp", 0)}, {"format", "bmp"}}.dump());
  ASSERT_TRUE(badOneShot);
  EXPECT_EQ(badOneShot->status, 400);
  EXPECT_EQ(bodyJson(badOneShot).value("field", ""), "format");
  EXPECT_EQ(del("/api/sessions/" + id)->status, 204);
}

}  // namespace
}  // namespace brdfa::itest
