// On the real device: environment importance sampling, MIS, full-range environments
// and the honesty of rel_error, each against an analytic truth or an independent reference.
#include <gtest/gtest.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <unistd.h>

#include "brdfa/renderer.h"

#include "core/scene_math.h"
#include "device_test.h"
#include "image_test_encoders.h"

namespace brdfa {
namespace {

constexpr double kPi = 3.14159265358979323846;

const SamplingMode kAllModes[] = {SamplingMode::Cosine, SamplingMode::Uniform, SamplingMode::Brdf,
                                  SamplingMode::Environment, SamplingMode::Mis};

double luminance(const float* rgb) { return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]; }

// Unit direction of equirect pixel centre (x + fx, y + fy) (mapping of renderer/src/assets/equirect.h).
glm::dvec3 equirectDirection(double u, double v) {
  const double phi = (u - 0.5) * 2.0 * kPi, theta = v * kPi;
  return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

class Estimators : public DeviceTest {
 protected:
  static void SetUpTestSuite() {
    DeviceTest::SetUpTestSuite();
    dir_ = std::filesystem::path(::testing::TempDir()) / ("brdfa-convergence-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    // Half-white sky: radiance 1 above the horizon, 0 below (row 63 of 128 ends at v = 0.5).
    registerEquirect("half_white", 256, 128, [](int, int y) { return y < 64 ? 1.0f : 0.0f; });
  }
  static void TearDownTestSuite() {
    DeviceTest::TearDownTestSuite();
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }

  static void registerEquirect(const std::string& name, int w, int h, const std::function<float(int, int)>& radiance) {
    std::vector<float> rgb(size_t(w) * h * 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float v = radiance(x, y);
        for (int c = 0; c < 3; ++c) rgb[(size_t(y) * w + x) * 3 + c] = v;
      }
    std::filesystem::path file = dir_ / (name + ".exr");
    std::ofstream(file, std::ios::binary) << testing::encodeExr(w, h, rgb, /*half=*/false);
    auto ok = renderer_->registerAsset(name, AssetKind::Environment, file.string());
    ASSERT_TRUE(ok.ok()) << ok.error().message;
  }

  // A 4 x 4 plane filling a `size`^2 view, turned `tiltDegrees` about X from facing the camera.
  static Scene planeScene(std::shared_ptr<const BrdfDefinition> brdf, const std::string& env, float tiltDegrees,
                          int size) {
    Scene s = sphereScene(std::move(brdf), env, size);
    SceneObject& o = s.objects[0];
    o.mesh = "plane";
    o.rotate = {90.0f + tiltDegrees, 0, 0};
    o.scale = {2.5f, 2.5f, 2.5f};
    return s;
  }

  // The plane's world normal, turned to face the camera (as the G-buffer stores it).
  static glm::dvec3 planeNormal(const Scene& s) {
    glm::mat4 m = modelMatrix(s.objects[0]);
    glm::dvec3 n = glm::normalize(glm::dvec3(glm::transpose(glm::inverse(m)) * glm::vec4(0, 1, 0, 0)));
    return n.z < 0 ? -n : n;
  }

  // A unit sphere in the hidden environment `env`, `size`^2 pixels, 64 samples a pass.
  static Scene sphereScene(std::shared_ptr<const BrdfDefinition> brdf, const std::string& env, int size) {
    Scene s;
    s.environment.name = env;
    s.environment.visible = false;
    s.render.width = s.render.height = size;
    s.render.samplesPerFrame = 64;
    SceneObject o;
    o.brdf = std::move(brdf);
    s.objects.push_back(o);
    return s;
  }

  // Renders until spp reaches `spp` (continuing the view's accumulation) and reads the frame.
  static Frame renderTo(RenderView& view, Scene& scene, int spp) {
    scene.render.maxSamples = spp;
    auto set = view.setScene(scene);  // a higher max_samples continues the accumulation
    EXPECT_TRUE(set.ok()) << set.error().message;
    return renderUntilDone(view);
  }

  static std::unique_ptr<RenderView> newView(const Scene& scene) {
    auto view = renderer_->createView();
    EXPECT_TRUE(view.ok());
    auto set = (*view)->setScene(scene);
    EXPECT_TRUE(set.ok()) << set.error().message;
    return std::move(view.value());
  }

  // Relative RMS difference over the pixels where `truth` is non-zero: the documented definition
  // of rel_error, sqrt(mean squared error) / mean luminance, with the truth's mean.
  static double relRms(const Frame& f, const std::function<double(size_t)>& truth, double truthVariance = 0) {
    double se = 0, lum = 0;
    size_t n = 0;
    for (size_t i = 0; i < size_t(f.width) * f.height; ++i) {
      const double t = truth(i);
      if (!(t > 0)) continue;
      const double d = luminance(&f.rgba32f[4 * i]) - t;
      se += d * d;
      lum += t;
      ++n;
    }
    return std::sqrt(std::max(0.0, se / n - truthVariance)) / (lum / n);
  }

  static inline std::filesystem::path dir_;
};

TEST_F(Estimators, HalfWhiteSkyMatchesItsAnalyticValueUnderEveryMode) {
  // A Lambertian lit by radiance 1 above the horizon reflects (1 + n_y) / 2.
  for (float tilt : {-40.0f, 25.0f}) {
    for (SamplingMode mode : kAllModes) {
      Scene s = planeScene(builtin("lambert"), "half_white", tilt, 32);
      s.objects[0].params["Kd"] = {1, 1, 1};
      s.render.sampling = mode;
      const double truth = (1.0 + planeNormal(s).y) / 2.0;
      auto view = newView(s);
      Frame f = renderTo(*view, s, 1024);
      double sum = 0, worst = 0;
      for (int i = 0; i < f.width * f.height; ++i) {
        sum += f.rgba32f[4 * i];
        worst = std::max(worst, std::abs(f.rgba32f[4 * i] - truth));
      }
      const double mean = sum / (f.width * f.height);
      EXPECT_NEAR(mean, truth, 0.01 * truth) << samplingModeName(mode) << " tilt " << tilt;
      // Every pixel: 1024 samples leave a few percent of noise per pixel (the honesty of the
      // error estimate is tested below); a bias would show as a wrong mean or a far pixel.
      EXPECT_LT(worst, 0.25 * truth) << samplingModeName(mode) << " tilt " << tilt;
    }
  }
}

// The G-buffer keeps normals in the octahedral map (lib/gbuffer_encoding.glsl), whose lower
// hemisphere (n.z < 0) is folded over the diagonals; a sphere seen from +z shows only normals
// with n.z > 0. Seen from -z, from near each axis and from an arbitrary side, a white
// Lambertian sphere in the half-white sky is (1 + n_y) / 2 at every pixel, with n where the
// pixel's ray meets the unit sphere: checked over blocks of 8 x 8 pixels, so a wrong unfolding
// anywhere (an error in n of order 1) shows.
TEST_F(Estimators, SphereSeenFromEverySideShowsItsNormalsInTheHalfWhiteSky) {
  struct Side {
    const char* name;
    float yaw, pitch;  // the camera looks along this, from 3 units away, at the sphere
  };
  const Side sides[] = {{"+z", 0, 0},       {"-z", 180, 0},          {"near -z", 179.9f, 0.05f},
                        {"+x", 90, 0},      {"-x", -90, 0},          {"above", 0, -89},
                        {"below", 180, 89}, {"arbitrary", 137, -23}, {"near +z", 0.05f, 0.1f}};
  constexpr int kSize = 64, kBlock = 8;
  for (const Side& side : sides) {
    Scene s = sphereScene(builtin("lambert"), "half_white", kSize);
    s.objects[0].params["Kd"] = {1, 1, 1};
    s.render.sampling = SamplingMode::Cosine;
    s.camera.yaw = side.yaw;
    s.camera.pitch = side.pitch;
    s.camera.position = {0, 0, 0};
    const glm::vec3 look = cameraFrame(s.camera, kSize, kSize).forward;
    s.camera.position = {-3 * look.x, -3 * look.y, -3 * look.z};
    const CameraFrame cam = cameraFrame(s.camera, kSize, kSize);
    auto view = newView(s);
    Frame f = renderTo(*view, s, 512);
    ASSERT_EQ(f.width, kSize);
    // Per block: the sums of the rendered and true values over interior pixels (rays passing
    // well inside the silhouette, clear of the tessellation's edge and the anti-aliasing).
    std::vector<double> got(kSize * kSize / (kBlock * kBlock)), want(got.size()), count(got.size());
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const glm::dvec2 ndc(2.0 * (x + 0.5) / kSize - 1.0, 1.0 - 2.0 * (y + 0.5) / kSize);
        const glm::dvec3 dir =
            glm::normalize(glm::dvec3(cam.forward) + ndc.x * cam.tanHalfFov * cam.aspect * glm::dvec3(cam.right) +
                           ndc.y * cam.tanHalfFov * glm::dvec3(cam.up));
        const glm::dvec3 origin(cam.position);
        const double b = glm::dot(origin, dir), c = glm::dot(origin, origin) - 1.0, disc = b * b - c;
        if (disc < 0.2) continue;  // outside, or within ~0.1 of the silhouette
        const glm::dvec3 n = origin + (-b - std::sqrt(disc)) * dir;
        const size_t block = size_t(y / kBlock) * (kSize / kBlock) + x / kBlock;
        got[block] += f.rgba32f[4 * (y * kSize + x)];
        want[block] += (1.0 + n.y) / 2.0;
        count[block] += 1;
      }
    double blocks = 0, worst = 0;
    for (size_t b = 0; b < got.size(); ++b) {
      if (count[b] < 16) continue;
      ++blocks;
      worst = std::max(worst, std::abs(got[b] - want[b]) / count[b]);
    }
    EXPECT_GE(blocks, 20) << side.name;
    // 512 cosine samples of a 0/1 sky: at most 0.022 of noise per pixel, 0.0055 per block of
    // 16 or more pixels; 0.03 is over 5 of those.
    EXPECT_LT(worst, 0.03) << "seen from " << side.name;
  }
}

TEST_F(Estimators, FurnaceStaysExactWithCosineAndMisIsTheBrdfSideThere) {
  Scene s = sphereScene(builtin("lambert"), "furnace", 48);
  s.objects[0].params["Kd"] = {1, 1, 1};
  for (SamplingMode mode : {SamplingMode::Cosine, SamplingMode::Mis}) {
    s.render.sampling = mode;
    auto view = newView(s);
    Frame f = renderTo(*view, s, 64);
    int covered = 0;
    for (int i = 0; i < f.width * f.height; ++i) {
      const float* px = &f.rgba32f[4 * i];
      if (px[0] == 0.0f) continue;  // background or a silhouette pixel's miss
      // Interior pixels only: a silhouette pixel averages object and (black) background.
      const int x = i % f.width, y = i / f.width;
      bool interior = x > 0 && y > 0 && x + 1 < f.width && y + 1 < f.height;
      for (int dy = -1; interior && dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) interior = interior && f.rgba32f[4 * ((y + dy) * f.width + x + dx)] != 0.0f;
      if (!interior) continue;
      ++covered;
      ASSERT_NEAR(px[0], 1.0f, 1e-5f) << samplingModeName(mode) << " pixel " << i;
    }
    EXPECT_GT(covered, 500);
    if (mode == SamplingMode::Mis) {
      EXPECT_EQ(f.stats.estimator, "brdf") << "mis in a constant environment is the BRDF side alone";
    }
  }
}

// A sun of 0.5 degrees diameter and radiance `sun` over a black sky, its edge antialiased by
// supersampling: irradiance L * solid angle * cos, reflected by a white Lambertian as E / pi.
TEST_F(Estimators, HalfDegreeSunFarAboveHalfRangeKeepsItsEnergy) {
  const glm::dvec3 sunDir = glm::normalize(glm::dvec3(0.3, 0.6, 0.75));
  const double radius = 0.25 * kPi / 180.0;
  const double sunSolidAngle = 2.0 * kPi * (1.0 - std::cos(radius));
  const int w = 2048, h = 1024;
  for (float sun : {1e5f, 1e6f}) {
    const std::string name = "sun" + std::to_string(int(std::log10(sun)));
    double energy = 0;  // the image's own integral of L over the sun, for the report
    registerEquirect(name, w, h, [&](int x, int y) {
      const glm::dvec3 c = equirectDirection((x + 0.5) / w, (y + 0.5) / h);
      if (glm::dot(c, sunDir) < std::cos(radius + 0.01)) return 0.0f;
      int inside = 0;
      const int n = 16;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
          inside +=
              glm::dot(equirectDirection((x + (i + 0.5) / n) / w, (y + (j + 0.5) / n) / h), sunDir) >= std::cos(radius);
      const double v = double(sun) * inside / (n * n);
      const double theta = (y + 0.5) / h * kPi;
      energy += v * (2.0 * kPi / w) * (kPi / h) * std::sin(theta);
      return float(v);
    });
    EXPECT_NEAR(energy, sun * sunSolidAngle, 0.002 * sun * sunSolidAngle) << "the test's own sun";
    for (SamplingMode mode : {SamplingMode::Mis, SamplingMode::Environment}) {
      Scene s = planeScene(builtin("lambert"), name, 0.0f, 32);
      s.objects[0].params["Kd"] = {1, 1, 1};
      s.render.sampling = mode;
      const glm::dvec3 n = planeNormal(s);
      const double truth = sun * sunSolidAngle * glm::dot(n, sunDir) / kPi;
      auto view = newView(s);
      Frame f = renderTo(*view, s, 256);
      double sum = 0;
      for (int i = 0; i < f.width * f.height; ++i) sum += f.rgba32f[4 * i];
      EXPECT_NEAR(sum / (f.width * f.height), truth, 0.01 * truth) << name << " " << samplingModeName(mode);
    }
  }
}

// rel_error against the true relative RMS error at 16 .. 16384 spp, for every mode: a Lambertian
// plane in the half-white sky, whose every pixel is (1 + n_y) / 2.
TEST_F(Estimators, RelErrorTracksTheTrueErrorInTheHalfWhiteSky) {
  for (SamplingMode mode : kAllModes) {
    Scene s = planeScene(builtin("lambert"), "half_white", 30.0f, 64);
    s.objects[0].params["Kd"] = {1, 1, 1};
    s.render.sampling = mode;
    const double truth = (1.0 + planeNormal(s).y) / 2.0;
    auto view = newView(s);
    for (int spp : {16, 256, 4096, 16384}) {
      Frame f = renderTo(*view, s, spp);
      ASSERT_EQ(f.stats.spp, uint64_t(spp));
      ASSERT_TRUE(f.stats.relError.has_value());
      const double trueError = relRms(f, [&](size_t) { return truth; });
      const double ratio = *f.stats.relError / trueError;
      std::printf("half-white %-11s %6d spp: rel_error %.3e, true %.3e, ratio %.3f\n", samplingModeName(mode), spp,
                  *f.stats.relError, trueError, ratio);
      EXPECT_GE(ratio, 0.75) << samplingModeName(mode) << " at " << spp;
      EXPECT_LE(ratio, 1.33) << samplingModeName(mode) << " at " << spp;
    }
  }
}

// The same for GGX 0.2 on a sphere in the sky with its sun. The truth is two independent
// 32768-spp references (other seeds, so they share no sample with the image tested):
// mean((x - r1)(x - r2)) estimates the mean squared error of x without bias, whatever the
// references' own noise.
TEST_F(Estimators, RelErrorTracksTheTrueErrorForGgxInTheSky) {
  Scene s = sphereScene(builtin("ggx"), "sky", 64);
  s.objects[0].params["roughness"] = {0.2f, 0.2f, 0.2f};
  Frame refs[2];
  for (int r = 0; r < 2; ++r) {
    Scene rs = s;
    rs.render.seed = uint32_t(r + 1);
    auto refView = newView(rs);
    refs[r] = renderTo(*refView, rs, 32768);
  }
  // Two independent images (seeds 0 and 3), pooled: twice the pixels steady both sides of the
  // ratio against the few highlight pixels that dominate them.
  std::unique_ptr<RenderView> views[2];
  Scene scenes[2] = {s, s};
  scenes[1].render.seed = 3;
  for (int k = 0; k < 2; ++k) views[k] = newView(scenes[k]);
  for (int spp : {16, 256, 4096, 16384}) {
    double estimated2 = 0, true2 = 0;
    for (int k = 0; k < 2; ++k) {
      Frame f = renderTo(*views[k], scenes[k], spp);
      ASSERT_TRUE(f.stats.relError.has_value());
      double se = 0, lum = 0;
      size_t n = 0;
      for (size_t i = 0; i < size_t(f.width) * f.height; ++i) {
        const double r1 = luminance(&refs[0].rgba32f[4 * i]), r2 = luminance(&refs[1].rgba32f[4 * i]);
        if (!(r1 + r2 > 0)) continue;  // background
        const double x = luminance(&f.rgba32f[4 * i]);
        se += (x - r1) * (x - r2);
        lum += 0.5 * (r1 + r2);
        ++n;
      }
      true2 += std::max(se / n, 0.0) / std::pow(lum / n, 2) / 2;
      estimated2 += std::pow(*f.stats.relError, 2) / 2;
    }
    const double ratio = std::sqrt(estimated2 / true2);
    std::printf("ggx 0.2 sky mis %6d spp: rel_error %.3e, true %.3e, ratio %.3f\n", spp, std::sqrt(estimated2),
                std::sqrt(true2), ratio);
    EXPECT_GE(ratio, 0.75) << spp;
    EXPECT_LE(ratio, 1.33) << spp;
  }
}

TEST_F(Estimators, SeedsGiveIndependentRendersAndTheSameSeedTheSameImage) {
  Scene s = sphereScene(builtin("ggx"), "sky", 32);
  Frame a = renderTo(*newView(s), s, 64);
  Frame b = renderTo(*newView(s), s, 64);
  s.render.seed = 7;
  Frame c = renderTo(*newView(s), s, 64);
  EXPECT_EQ(a.rgba32f, b.rgba32f);
  EXPECT_NE(a.rgba32f, c.rgba32f);
}

TEST_F(Estimators, EstimatorAndWarningsNameWhatRuns) {
  Scene s = sphereScene(builtin("ggx"), "sky", 32);
  auto view = newView(s);
  EXPECT_EQ(view->stats().estimator, "mis(environment+brdf)");
  EXPECT_TRUE(view->stats().warnings.empty());
  // Several objects: each distinct estimator once, in object order.
  SceneObject second = s.objects[0];
  second.brdf = builtin("oren_nayar");  // no sampler
  second.translate = {1.5f, 0, 0};
  s.objects.push_back(second);
  ASSERT_TRUE(view->setScene(s).ok());
  EXPECT_EQ(view->stats().estimator, "mis(environment+brdf), mis(environment+cosine)");
  s.objects.erase(s.objects.begin());
  ASSERT_TRUE(view->setScene(s).ok());
  EXPECT_EQ(view->stats().estimator, "mis(environment+cosine)");
  // A sampler without pdfBRDF cannot take part in MIS: said in stats and at validation.
  BrdfDefinition noPdf = *builtin("ggx");
  const size_t at = noPdf.sampleShader.find("float pdfBRDF(");
  ASSERT_NE(at, std::string::npos);
  noPdf.sampleShader.replace(at, std::string("float pdfBRDF(").size(), "float ggxPdf(");
  size_t call;
  while ((call = noPdf.sampleShader.find("pdfBRDF(")) != std::string::npos)
    noPdf.sampleShader.replace(call, 8, "ggxPdf(");
  s.objects[0].brdf = std::make_shared<BrdfDefinition>(noPdf);
  s.objects[0].brdfName = "ggx_nopdf";
  ASSERT_TRUE(view->setScene(s).ok());
  EXPECT_EQ(view->stats().estimator, "mis(environment+cosine)");
  ASSERT_EQ(view->stats().warnings.size(), 1u);
  EXPECT_NE(view->stats().warnings[0].find("cannot take part in MIS"), std::string::npos);
  auto compiled = renderer_->compileBrdf(noPdf);
  ASSERT_TRUE(compiled.ok());
  bool warned = false;
  for (const Diagnostic& d : compiled->warnings)
    warned = warned || d.message.find("multiple importance") != std::string::npos;
  EXPECT_TRUE(warned);
}

TEST_F(Estimators, TargetErrorStopsRenderingAndIsReportedApartFromMaxSamples) {
  Scene s = sphereScene(builtin("lambert"), "sky", 32);
  s.render.targetError = 0.02;
  s.render.maxSamples = 1 << 20;
  auto view = newView(s);
  FrameStats st;
  for (int guard = 0; guard < 100000; ++guard) {
    auto pass = view->renderPass();
    ASSERT_TRUE(pass.ok());
    st = pass.value();
    if (st.done()) break;
  }
  EXPECT_TRUE(st.converged);
  EXPECT_FALSE(st.maxSamplesReached);
  ASSERT_TRUE(st.relError.has_value());
  EXPECT_LE(*st.relError, 0.02);
  EXPECT_GE(st.spp, kMinSppForTarget);
  const uint64_t spp = st.spp;
  EXPECT_EQ(view->renderPass()->spp, spp) << "a converged view renders nothing more";
  s.render.targetError = 0.0;  // no target: max_samples ends it
  s.render.maxSamples = int(spp) + 32;
  ASSERT_TRUE(view->setScene(s).ok());
  while (!view->renderPass()->done()) {
  }
  EXPECT_FALSE(view->stats().converged);
  EXPECT_TRUE(view->stats().maxSamplesReached);
}

TEST_F(Estimators, EnvironmentSamplerDrawsWhatItsPdfSays) {
  // A bright spot of a few pixels far above half range over a dim sky, as a captured sun is.
  registerEquirect("spot", 512, 256,
                   [](int x, int y) { return x >= 300 && x < 302 && y >= 60 && y < 62 ? 2e5f : 2.0f; });
  for (const char* name : {"sky", "studio", "cornell", "half_white", "spot"}) {
    auto report = renderer_->checkEnvironmentSampler(name);
    ASSERT_TRUE(report.ok()) << name << ": " << report.error().message;
    std::printf(
        "%-10s cells p %.3g, positions p %.3g, max |z| %.2f over %u bins, pdf mismatch %.2g (host %.2g, %.2g of "
        "draws), "
        "length %.2g\n",
        name, report->cellChi2PValue, report->positionChi2PValue, report->maxSolidAngleZ, report->solidAngleBins,
        report->maxPdfMismatch, report->hostPdfMismatch, report->pdfMismatchFraction, report->maxLengthError);
    EXPECT_TRUE(report->passed()) << name;
    EXPECT_GE(report->solidAngleBins, 100u) << name;
  }
  EXPECT_FALSE(renderer_->checkEnvironmentSampler("furnace").ok()) << "the furnace has no table";
}

}  // namespace
}  // namespace brdfa
