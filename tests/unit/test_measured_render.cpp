// Measured BRDFs on the real device: tables made in MERL's layout from known functions
// (tests/support/merl_files.h), registered like uploads, looked up by measuredMERL() in the
// analysis kernels and in rendered images, against the analytic BRDF they were made from.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <unistd.h>

#include "brdfa/measured.h"
#include "brdfa/renderer.h"

#include "device_test.h"
#include "merl_files.h"

namespace brdfa {
namespace {

constexpr double kPi = 3.14159265358979323846;
const testsupport::Rgb kF0{0.95, 0.64, 0.54};  // ggx.brdf's default F0
constexpr double kAlpha = 0.3;                 // and roughness

class MeasuredRender : public DeviceTest {
 protected:
  static void SetUpTestSuite() {
    DeviceTest::SetUpTestSuite();
    dir_ = std::filesystem::path(::testing::TempDir()) / ("brdfa-measured-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    ggxFile_ = writeFile("ggx.binary", testsupport::ggxMerl(kAlpha, kF0));
    lambertFile_ = writeFile("lambert.binary", testsupport::lambertMerl({1, 1, 1}));
    for (auto [name, file] : {std::pair{"merl_ggx", ggxFile_}, std::pair{"merl_white", lambertFile_}}) {
      auto ok = renderer_->registerAsset(name, AssetKind::Measured, file);
      ASSERT_TRUE(ok.ok()) << ok.error().message;
    }
  }
  static void TearDownTestSuite() {
    DeviceTest::TearDownTestSuite();
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  static std::string writeFile(const std::string& name, const std::string& bytes) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  static std::shared_ptr<const BrdfDefinition> measured(const std::string& table) {
    auto brdf = measuredBrdf(table);
    EXPECT_TRUE(brdf.ok()) << brdf.error().message;
    return brdf.ok() ? std::make_shared<BrdfDefinition>(brdf.value()) : nullptr;
  }

  // `s` (one object, hidden environment) rendered to its end with `analytic` and with the
  // measured table `table` as the object's BRDF: equal samples of the same sequences.
  static std::pair<Frame, Frame> renderBoth(Scene s, std::shared_ptr<const BrdfDefinition> analytic,
                                            const std::string& table) {
    SceneObject o;
    o.brdf = std::move(analytic);
    s.environment.visible = false;
    s.objects = {o};
    auto analyticView = viewWithScene(*renderer_, s);
    s.objects[0].brdf = measured(table);
    auto measuredView = viewWithScene(*renderer_, s);
    EXPECT_TRUE(analyticView && measuredView);
    if (!analyticView || !measuredView) return {};
    return {renderUntilDone(*analyticView), renderUntilDone(*measuredView)};
  }

  static inline std::filesystem::path dir_;
  static inline std::string ggxFile_, lambertFile_;
};

// Pairs above the horizon, N = +z, from grazing to normal and in every azimuth.
std::vector<DirectionPair> randomPairs(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto dir = [&] {
    const double z = std::max(2e-3, u(rng)), phi = 2 * kPi * u(rng), s = std::sqrt(1 - z * z);
    return Vec3{float(s * std::cos(phi)), float(s * std::sin(phi)), float(z)};
  };
  std::vector<DirectionPair> pairs;
  for (int k = 0; k < n; ++k) pairs.push_back({dir(), dir()});
  return pairs;
}

TEST_F(MeasuredRender, DeviceLookupIsTheHostLookup) {
  const std::vector<DirectionPair> pairs = randomPairs(4000, 1);
  auto values = renderer_->evaluateBrdf(*measured("merl_ggx"), {ParamSetting{}}, pairs);
  ASSERT_TRUE(values.ok()) << values.error().message;
  auto table = readMerl(testsupport::ggxMerl(kAlpha, kF0));
  ASSERT_TRUE(table.ok());
  for (size_t i = 0; i < pairs.size(); ++i) {
    const Vec3 host = lookupMerlInterpolated(*table, pairs[i].light, pairs[i].view);
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR((*values)[i][c], host[c], 2e-3 * std::max(1.0f, host[c])) << "pair " << i << " channel " << c;
  }
}

// The table's sampler (a fitted GGX lobe mixed with the cosine) against its own pdf and BRDF():
// the renderer's chi-square and weight checks at every normal and view they test.
TEST_F(MeasuredRender, SamplerPassesTheSamplerChecks) {
  for (const char* table : {"merl_ggx", "merl_white"}) {
    auto report = renderer_->checkSampler(*measured(table));
    ASSERT_TRUE(report.ok()) << report.error().message;
    EXPECT_TRUE(report->chi2Run) << table;
    EXPECT_TRUE(report->passed()) << table << ": " << report->worst << " " << report->chi2Failure;
    EXPECT_GT(report->minChi2PValue, report->chi2Threshold) << table;
  }
}

// The polar plot's slice (the incidence plane, V at several angles, L over the whole plane):
// the measured table on the device departs from the analytic GGX no more than the host's
// interpolation of the same table does, plus float rounding.
TEST_F(MeasuredRender, PolarSliceFollowsAnalyticGgxWithinTheTablesInterpolationError) {
  std::vector<DirectionPair> pairs;
  for (double thetaV : {0.0, 30.0, 60.0, 80.0})
    for (int k = -89; k <= 89; ++k) {
      const double tv = thetaV * kPi / 180, tl = k * kPi / 180;
      pairs.push_back({Vec3{float(std::sin(tl)), 0.0f, float(std::cos(tl))},
                       Vec3{float(-std::sin(tv)), 0.0f, float(std::cos(tv))}});
    }
  auto measuredValues = renderer_->evaluateBrdf(*measured("merl_ggx"), {ParamSetting{}}, pairs);
  ASSERT_TRUE(measuredValues.ok()) << measuredValues.error().message;
  auto analytic = renderer_->evaluateBrdf(*builtin("ggx"), {ParamSetting{}}, pairs);
  ASSERT_TRUE(analytic.ok()) << analytic.error().message;
  auto table = readMerl(testsupport::ggxMerl(kAlpha, kF0));
  ASSERT_TRUE(table.ok());
  double deviceErr = 0, hostErr = 0, ref = 0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const Vec3 host = lookupMerlInterpolated(*table, pairs[i].light, pairs[i].view);
    const double a = (*analytic)[i][1], m = (*measuredValues)[i][1];
    deviceErr += (m - a) * (m - a);
    hostErr += (host[1] - a) * (host[1] - a);
    ref += a * a;
  }
  const double deviceRel = std::sqrt(deviceErr / ref), hostRel = std::sqrt(hostErr / ref);
  EXPECT_LT(deviceRel, hostRel * 1.01 + 1e-4) << "host interpolation error " << hostRel;
  EXPECT_LT(deviceRel, 0.02);
}

// Cosine sampling in the furnace makes every sample of a white Lambertian exactly 1: the
// table's sphere is the analytic one's, pixel for pixel, edges included.
TEST_F(MeasuredRender, WhiteLambertTableRendersAsOneInTheFurnace) {
  Scene s;
  s.environment.name = "furnace";
  s.render.width = s.render.height = 64;
  s.render.maxSamples = 16;
  s.render.sampling = SamplingMode::Cosine;
  const auto [a, m] = renderBoth(s, inlineBrdf(kWhiteLambert), "merl_white");
  ASSERT_EQ(a.rgba32f.size(), m.rgba32f.size());
  size_t ones = 0;
  for (size_t i = 0; i < a.rgba32f.size(); ++i) {
    if (i % 4 == 3) continue;
    ASSERT_NEAR(m.rgba32f[i], a.rgba32f[i], 1e-4) << "pixel " << i / 4;
    ones += std::abs(m.rgba32f[i] - 1.0f) < 1e-4f ? 1 : 0;
  }
  EXPECT_GT(ones, size_t(3 * 64 * 64 / 3));  // the sphere's interior
}

// The sphere in the sky, analytic GGX against the table made from it, equal samples of the
// same sequences (environment sampling draws the same directions for both): the relative MSE
// (mean of (m - a)^2 / (a^2 + 0.01) over the sphere) is the table's, not the noise's.
TEST_F(MeasuredRender, MeasuredGgxImageIsTheAnalyticGgxImageWithin2PercentRelMse) {
  Scene s;
  s.environment.name = "sky";
  s.render.width = s.render.height = 96;
  s.render.samplesPerFrame = 64;
  s.render.maxSamples = 256;
  s.render.sampling = SamplingMode::Environment;
  const auto [a, m] = renderBoth(s, builtin("ggx"), "merl_ggx");
  ASSERT_EQ(a.rgba32f.size(), m.rgba32f.size());
  double sum = 0;
  size_t n = 0;
  for (size_t p = 0; p < size_t(a.width) * a.height; ++p) {
    const float* x3 = &a.rgba32f[4 * p];
    if (x3[0] == 0 && x3[1] == 0 && x3[2] == 0) continue;  // the hidden background
    for (int c = 0; c < 3; ++c) {
      const double x = a.rgba32f[4 * p + c], y = m.rgba32f[4 * p + c];
      sum += (y - x) * (y - x) / (x * x + 0.01);
      ++n;
    }
  }
  ASSERT_GT(n, size_t(3 * 96 * 96 / 4));
  const double relMse = sum / double(n);
  // The promise is 2 %; the bound that can fail is tighter: analytic GGX at roughness 0.33
  // instead of 0.3 is 1.3e-3 from it on this scene, the table about 1e-6.
  EXPECT_LT(relMse, 0.02);
  EXPECT_LT(relMse, 1e-4);
  RecordProperty("relMSE", std::to_string(relMse));
}

TEST_F(MeasuredRender, TableIsCountedInTheMemoryBudget) {
  const uint64_t before = renderer_->counters().memory.assets;
  const std::string file = writeFile("again.binary", testsupport::lambertMerl({0.5, 0.5, 0.5}));
  ASSERT_TRUE(renderer_->registerAsset("merl_counted", AssetKind::Measured, file).ok());
  // The table, and the sampling proposal's four floats after it.
  EXPECT_EQ(renderer_->counters().memory.assets, before + 3 * kMerlBins * sizeof(float) + 16);
  EXPECT_EQ(renderer_->counters().memory.transfers, 0u);  // the file and staging are given back
}

// A renderer whose budget is `headroom` above what a renderer holds after it starts, and the
// registration of a 35 MB table there. The table needs about 88 MB while it loads (the file,
// the decoded table and its device copy) and keeps 17.5 MB.
Result<void> registerWithHeadroom(uint64_t startBytes, uint64_t headroom, const std::string& path) {
  RendererOptions options;
  options.shaderDir = std::string(BRDFA_SOURCE_DIR) + "/shaders";
  options.memoryBudgetBytes = startBytes + headroom;
  auto renderer = Renderer::create(options);
  if (!renderer.ok()) return renderer.takeError();
  return (*renderer)->registerAsset("merl_big", AssetKind::Measured, path);
}

TEST(MeasuredBudget, ATableTheBudgetCannotHoldIsRefusedAtRegistration) {
  const std::string path =
      (std::filesystem::path(::testing::TempDir()) / ("brdfa-budget-" + std::to_string(::getpid()) + ".binary"))
          .string();
  std::ofstream(path, std::ios::binary) << testsupport::lambertMerl({0.5, 0.5, 0.5});
  uint64_t startBytes = 0;
  {
    RendererOptions options;
    options.shaderDir = std::string(BRDFA_SOURCE_DIR) + "/shaders";
    options.memoryBudgetBytes = 64ull << 30;
    auto probe = Renderer::create(options);
    ASSERT_TRUE(probe.ok()) << probe.error().message;
    startBytes = (*probe)->counters().memory.total();
  }
  auto refused = registerWithHeadroom(startBytes, 48ull << 20, path);
  auto accepted = registerWithHeadroom(startBytes, 300ull << 20, path);
  std::filesystem::remove(path);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::OverBudget) << refused.error().message;
  EXPECT_NE(refused.error().message.find("merl_big"), std::string::npos) << refused.error().message;
  EXPECT_TRUE(accepted.ok()) << accepted.error().message;
}

TEST_F(MeasuredRender, AnUnregisteredTableIsNotFound) {
  Scene s;
  SceneObject o;
  o.brdf = measured("merl_never_registered");
  s.objects.push_back(o);
  auto view = renderer_->createView();
  ASSERT_TRUE(view.ok());
  auto set = (*view)->setScene(s);
  ASSERT_FALSE(set.ok());
  EXPECT_EQ(set.error().code, ErrorCode::NotFound) << set.error().message;
  EXPECT_EQ(set.error().field, "objects[0].brdf");
}

}  // namespace
}  // namespace brdfa
