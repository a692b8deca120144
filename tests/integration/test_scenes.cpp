// Scenes through the real server: an uploaded equirectangular HDR lights a Lambert
// sphere exactly as the irradiance integral says, several objects with their own BRDFs and
// textures render and count their vertices, and the camera pitch is clamped.
#include <cmath>
#include <string>

#include "image_test_encoders.h"
#include "server_fixture.h"

namespace brdfa::itest {
namespace {

using nlohmann::json;

// Radiance 1 above the horizon (world +y: the upper half of the image rows), 0 below.
std::string upperHemisphereHdr(int width, int height) {
  std::vector<float> rgb(size_t(width) * height * 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) rgb[(size_t(y) * width + x) * 3 + c] = y < height / 2 ? 1.0f : 0.0f;
  return testing::encodeHdr(width, height, rgb);
}

// Unit sphere at the origin, camera at (0, 0, 3) looking down -z with a 45 degree field of
// view: the world normal where the ray through pixel (x, y)'s centre meets the sphere, and how
// far inside the silhouette (1 - closest approach of the ray to the centre).
struct Hit {
  bool inside = false;
  double nx = 0, ny = 0, nz = 0, margin = 0;
};

Hit sphereHit(int x, int y, int size) {
  const double tanHalf = std::tan(22.5 * 3.14159265358979323846 / 180.0);
  const double dx = (2.0 * (x + 0.5) / size - 1.0) * tanHalf, dy = (1.0 - 2.0 * (y + 0.5) / size) * tanHalf;
  const double len = std::sqrt(dx * dx + dy * dy + 1.0);
  const double ux = dx / len, uy = dy / len, uz = -1.0 / len;
  // |o + t u|^2 = 1 with o = (0, 0, 3): t^2 + 2 (o.u) t + 8 = 0.
  const double b = 3.0 * uz, disc = b * b - 8.0;
  Hit h;
  if (disc <= 0) return h;
  const double t = -b - std::sqrt(disc);
  h.inside = true;
  h.nx = ux * t;
  h.ny = uy * t;
  h.nz = 3.0 + uz * t;
  h.margin = 1.0 - std::sqrt(9.0 - b * b);  // closest approach sqrt(|o|^2 - (o.u)^2)
  return h;
}

class Scenes : public ServerTest {
 protected:
  // Uploads `bytes` as `fileName`; the new asset's id, or "" (with a test failure).
  static std::string upload(const std::string& bytes, const std::string& fileName, const std::string& kind) {
    httplib::MultipartFormDataItems items = {{"file", bytes, fileName, "application/octet-stream"},
                                             {"kind", kind, "", ""}};
    auto r = server_->client()->Post("/api/assets", items);
    EXPECT_TRUE(r && r->status == 201) << (r ? r->body : "no response");
    if (!r || r->status != 201) return "";
    return bodyJson(r).value("id", "");
  }

  static Image frame(const std::string& session, int minSpp) {
    auto r = get("/api/sessions/" + session + "/frame?format=pfm&min_spp=" + std::to_string(minSpp));
    Image img;
    EXPECT_TRUE(r && r->status == 200) << (r ? r->body : "no response");
    if (r && r->status == 200) {
      EXPECT_TRUE(decodeImage(r->body, img));
    }
    return img;
  }

  // The vertex count the server reports for a scene of `objects`.
  static uint64_t verticesOf(const json& objects) {
    json scene = {{"environment", {{"name", "furnace"}, {"visible", false}}},
                  {"objects", objects},
                  {"render", {{"width", 64}, {"height", 64}, {"max_samples", 1}}}};
    auto r = put("/api/sessions/default/scene", scene.dump());
    EXPECT_TRUE(r && r->status == 200) << (r ? r->body : "no response");
    auto stats = bodyJson(get("/api/sessions/default/stats"));
    return stats.value("vertices", uint64_t(0));
  }
};

// A white Lambertian sphere under an uploaded HDR that is 1 above the
// horizon and 0 below reflects E(n) / pi = (1 + n_y) / 2 at every pixel (the cosine-weighted
// fraction of the hemisphere around n that lies above the horizon). Under every
// sampling mode, the image matches within 1% at 1024 samples.
TEST_F(Scenes, UploadedHdrHemisphereLightsALambertSphereAsTheIrradianceIntegralSays) {
  const std::string id = upload(upperHemisphereHdr(512, 256), "hemisphere.hdr", "environment");
  ASSERT_FALSE(id.empty());
  const int size = 128;
  for (const char* sampling : {"cosine", "uniform", "brdf", "environment", "mis"}) {
    json scene = {
        {"environment", {{"name", id}, {"visible", false}}},
        {"objects", json::array({{{"mesh", "sphere"}, {"brdf", "lambert"}, {"params", {{"Kd", {1, 1, 1}}}}}})},
        {"render",
         {{"width", size},
          {"height", size},
          {"max_samples", 1024},
          {"samples_per_frame", 64},
          {"sampling", sampling}}}};
    auto put = ServerTest::put("/api/sessions/default/scene", scene.dump());
    ASSERT_TRUE(put && put->status == 200) << (put ? put->body : "no response");
    Image img = frame("default", 1024);
    ASSERT_EQ(img.width, size);

    double worst = 0, worstRelative = 0, signedSum = 0, expectedSum = 0;
    int tested = 0;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        Hit h = sphereHit(x, y, size);
        // Pixels a full pixel inside the silhouette (edge pixels also see the hidden background).
        if (!h.inside || h.margin < 0.03) continue;
        const double expected = 0.5 * (1.0 + h.ny);
        const double got = img.at(x, y, 1);
        worst = std::max(worst, std::fabs(got - expected));
        if (expected >= 0.5) worstRelative = std::max(worstRelative, std::fabs(got - expected) / expected);
        signedSum += got - expected;
        expectedSum += expected;
        ++tested;
      }
    std::printf("  %-11s %d pixels: max |error| %.4f, max relative error (expected >= 0.5) %.4f, mean error %+.5f\n",
                sampling, tested, worst, worstRelative, signedSum / tested);
    EXPECT_GT(tested, 5000);
    // The image within 1% (no bias in any mode), and no pixel far off.
    EXPECT_LT(std::fabs(signedSum) / expectedSum, 0.01) << sampling;
    EXPECT_LT(worst, 0.15) << sampling;
    if (std::string(sampling) == "cosine") {
      // Cosine sampling of a Lambertian leaves only the noise of the step in radiance: within
      // 3% at every pixel (each pixel is two independent randomised-QMC estimates of 512
      // samples, the price of an honest rel_error), and the mean error far smaller.
      EXPECT_LT(worst, 0.03);
      EXPECT_LT(worstRelative, 0.03);
      EXPECT_LT(std::fabs(signedSum / tested), 0.001);
    }
  }
}

TEST_F(Scenes, ThreeObjectsWithThreeBrdfsAndTexturesRenderAndCountTheirVertices) {
  auto saved = put("/api/brdfs/textured_lambert", kTexturedLambert, "text/plain");
  ASSERT_TRUE(saved && (saved->status == 200 || saved->status == 201)) << (saved ? saved->body : "no response");
  const json sphere = {{"mesh", "sphere"},
                       {"brdf", "textured_lambert"},
                       {"textures", {"checker"}},
                       {"translate", {-1.1, 0, 0}},
                       {"scale", {0.5, 0.5, 0.5}}};
  const json cube = {{"mesh", "cube"}, {"brdf", "ggx"}, {"rotate", {20, 30, 0}}, {"scale", {0.4, 0.4, 0.4}}};
  const json torus = {
      {"mesh", "torus"},          {"brdf", "ward"},       {"textures", {{{"name", "uv_grid"}, {"srgb", false}}}},
      {"translate", {1.1, 0, 0}}, {"rotate", {60, 0, 0}}, {"scale", {0.5, 0.5, 0.5}}};
  // The UV sphere has (128 + 1) x (64 + 1) vertices (a seam column and pole rows), the cube 24.
  EXPECT_EQ(verticesOf(json::array({sphere})), 129u * 65u);
  EXPECT_EQ(verticesOf(json::array({cube})), 24u);
  const uint64_t torusVertices = verticesOf(json::array({torus}));
  EXPECT_GT(torusVertices, 1000u);

  json scene = {{"environment", {{"name", "furnace"}, {"visible", false}}},
                {"objects", json::array({sphere, cube, torus})},
                {"render", {{"width", 192}, {"height", 64}, {"max_samples", 16}, {"samples_per_frame", 16}}},
                {"camera", {{"position", {0, 0, 3.2}}, {"fov", 30}}}};
  auto put = ServerTest::put("/api/sessions/default/scene", scene.dump());
  ASSERT_TRUE(put && put->status == 200) << (put ? put->body : "no response");
  Image img = frame("default", 16);
  ASSERT_EQ(img.width, 192);
  auto stats = bodyJson(get("/api/sessions/default/stats"));
  EXPECT_EQ(stats.value("vertices", uint64_t(0)), 129u * 65u + 24u + torusVertices);
  // The scene reads back with its textures.
  json back = bodyJson(get("/api/sessions/default/scene"));
  EXPECT_EQ(back["objects"][0]["textures"][0]["name"], "checker");
  EXPECT_EQ(back["objects"][2]["textures"][0]["srgb"], false);

  // Each third of the image shows its object; the checker makes the furnace-lit textured sphere
  // two-toned (the checker's sRGB 0.2 and 0.8 greys, linear 0.033 and 0.60), where an
  // untextured white Lambertian would be exactly 1.
  auto countIn = [&](int x0, int x1, auto predicate) {
    int n = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = x0; x < x1; ++x) n += predicate(img.at(x, y, 1)) ? 1 : 0;
    return n;
  };
  EXPECT_GT(countIn(0, 64, [](float v) { return v > 0.5f && v < 0.7f; }), 50);    // light squares
  EXPECT_GT(countIn(0, 64, [](float v) { return v > 0.01f && v < 0.06f; }), 50);  // dark squares
  EXPECT_EQ(countIn(0, 64, [](float v) { return v > 0.95f; }), 0);
  EXPECT_GT(countIn(64, 128, [](float v) { return v > 0.05f; }), 100);   // the GGX cube
  EXPECT_GT(countIn(128, 192, [](float v) { return v > 0.05f; }), 100);  // the Ward torus
}

TEST_F(Scenes, UnknownTexturesAreNotFoundAndTooManyAreRefused) {
  json scene = furnaceScene("lambert", json::object(), 32, 4);
  scene["objects"][0]["textures"] = {"no_such_texture"};
  auto r = put("/api/sessions/default/scene", scene.dump());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404) << r->body;
  EXPECT_NE(r->body.find("objects[0].textures[0]"), std::string::npos) << r->body;
  scene["objects"][0]["textures"] = {"checker", "checker", "checker", "checker", "checker"};
  r = put("/api/sessions/default/scene", scene.dump());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400) << r->body;
}

TEST_F(Scenes, CameraPitchIsClampedToEightyNineDegrees) {
  json scene = furnaceScene("lambert", json::object(), 32, 4);
  scene["camera"] = {{"pitch", 120}};
  auto r = put("/api/sessions/default/scene", scene.dump());
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "no response");
  EXPECT_EQ(bodyJson(get("/api/sessions/default/scene"))["camera"]["pitch"], 89);
  scene["camera"] = {{"pitch", -1000}};
  r = put("/api/sessions/default/scene", scene.dump());
  ASSERT_TRUE(r && r->status == 200);
  EXPECT_EQ(bodyJson(get("/api/sessions/default/scene"))["camera"]["pitch"], -89);
}

}  // namespace
}  // namespace brdfa::itest
