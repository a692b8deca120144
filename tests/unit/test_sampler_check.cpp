// BRDF importance samplers (`::begin sample`): every built-in one passes the sampler checks,
// broken ones fail them, and rendering with them is unbiased and less noisy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "brdfa/renderer.h"

#include "old_ggx_brdf.h"

namespace brdfa {
namespace {

std::string readText(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class Samplers : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    RendererOptions options;
    options.shaderDir = std::string(BRDFA_SOURCE_DIR) + "/shaders";
    renderer_ = Renderer::create(options).value();
  }
  static void TearDownTestSuite() { renderer_.reset(); }
  static BrdfDefinition parse(const std::string& text) {
    auto def = parseBrdf(text);
    EXPECT_TRUE(def.ok()) << (def.ok() ? "" : def.error().message);
    return def.ok() ? def.value() : BrdfDefinition{};
  }
  static inline std::shared_ptr<Renderer> renderer_;
};

TEST_F(Samplers, EveryBuiltinSamplerMatchesItsPdfAndItsBrdf) {
  int withSampler = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(BRDFA_SOURCE_DIR) + "/shaders/brdfs")) {
    BrdfDefinition def = parse(readText(entry.path()));
    if (!def.hasSampler()) continue;
    ++withSampler;
    auto r = renderer_->checkSampler(def);
    ASSERT_TRUE(r.ok()) << entry.path() << ": " << r.error().message;
    EXPECT_TRUE(r->passed()) << entry.path().filename() << ": worst: " << r->worst << "; mismatch "
                             << r->maxValueMismatch << ", cell z " << r->maxCellZ << " over " << r->cellsTested
                             << " cells, albedo z " << r->maxAlbedoZ << ", chi2 p " << r->minChi2PValue
                             << " (threshold " << r->chi2Threshold << ") " << r->chi2Failure << ", pdf mismatch "
                             << r->maxPdfMismatch << ", length error " << r->maxLengthError << ", pdf > 0 below "
                             << "the horizon " << r->pdfBelowHorizon;
    EXPECT_GT(r->cellsTested, 20u) << entry.path().filename();
    // Every built-in sampler states its density, so the chi-square test runs and passes.
    EXPECT_TRUE(r->chi2Run) << entry.path().filename();
    EXPECT_TRUE(r->chi2Failure.empty()) << entry.path().filename() << ": " << r->chi2Failure;
    EXPECT_GE(r->minChi2PValue, r->chi2Threshold) << entry.path().filename();
    EXPECT_LT(r->maxPdfMismatch, 1e-3) << entry.path().filename();
    EXPECT_LT(r->maxLengthError, 1e-4) << entry.path().filename();
    EXPECT_EQ(r->pdfBelowHorizon, 0u) << entry.path().filename();
    EXPECT_EQ(r->configs.size(), r->configurations);
    EXPECT_EQ(r->chi2PValues.size(), r->configurations);
    EXPECT_LT(r->ms, 3000.0) << entry.path().filename() << " took " << r->ms << " ms";
    std::cout << "[ sampler  ] " << entry.path().filename().string() << ": " << r->configurations
              << " configurations x " << r->samplesPerConfiguration << " samples in " << r->ms << " ms; min chi2 p "
              << r->minChi2PValue << " (threshold " << r->chi2Threshold << "), worst: " << r->worst << "\n";
  }
  EXPECT_GE(withSampler, 6);  // lambert, ggx, phong_normalized, blinn_phong_normalized, ward, cook_torrance
}

// A white Lambert file with a sample section built from pieces: PDF_FUNCTION (a pdfBRDF
// definition, or nothing), DRAW (r, phi, z from u), PDF_EXPR (the pdf sampleBRDF reports) and
// VALUE_EXPR (the value it returns).
const char* kLambertWithSampler = R"(analytic
::begin parameters
color Kd 1 1 1
::end parameters
::begin shader
const float PI = 3.14159265358979323846;
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd / PI; }
::end shader
::begin sample
// float pdfBRDF( in a comment is not a definition
PDF_FUNCTION
vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, out float pdf) {
    DRAW
    L = X * (r * cos(phi)) + Y * (r * sin(phi)) + N * z;
    pdf = PDF_EXPR;
    return VALUE_EXPR;
}
::end sample
)";

const char* kCosineDraw = "float r = sqrt(u.x), phi = 2.0 * PI * u.y, z = sqrt(max(0.0, 1.0 - u.x));";
const char* kUniformDraw = "float z = 1.0 - u.x, r = sqrt(max(0.0, 1.0 - z * z)), phi = 2.0 * PI * u.y;";

std::string lambertSampler(const std::string& pdfFunction, const std::string& draw, const std::string& pdf,
                           const std::string& value) {
  std::string s = kLambertWithSampler;
  s.replace(s.find("PDF_FUNCTION"), 12, pdfFunction);
  s.replace(s.find("DRAW"), 4, draw);
  s.replace(s.find("PDF_EXPR"), 8, pdf);
  s.replace(s.find("VALUE_EXPR"), 10, value);
  return s;
}

// Without pdfBRDF: only the cell, albedo and value checks run.
std::string lambertVariant(const std::string& pdf, const std::string& value, const char* draw = kCosineDraw) {
  return lambertSampler("", draw, pdf, value);
}

// With pdfBRDF { return FUNCTION; }, and sampleBRDF returning BRDF().
std::string lambertWithPdf(const std::string& draw, const std::string& returned, const std::string& function) {
  return lambertSampler("float pdfBRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return " + function + "; }", draw,
                        returned, "BRDF(L, V, N, X, Y)");
}

TEST_F(Samplers, ACorrectSamplerPasses) {
  auto r = renderer_->checkSampler(parse(lambertVariant("z / PI", "BRDF(L, V, N, X, Y)")));
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->passed()) << r->maxCellZ << " " << r->maxAlbedoZ << " " << r->maxValueMismatch;
}

TEST_F(Samplers, AWrongPdfFails) {
  // The uniform pdf for cosine-distributed samples: wrong everywhere but at one angle.
  auto r = renderer_->checkSampler(parse(lambertVariant("1.0 / (2.0 * PI)", "BRDF(L, V, N, X, Y)")));
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->passed());
  EXPECT_GT(r->maxCellZ, 6.0);  // 16384 samples per configuration
}

TEST_F(Samplers, AValueThatIsNotTheBrdfFails) {
  auto r = renderer_->checkSampler(parse(lambertVariant("z / PI", "0.5 * BRDF(L, V, N, X, Y)")));
  ASSERT_TRUE(r.ok());
  EXPECT_GT(r->maxValueMismatch, 0.1);
  EXPECT_FALSE(r->passed());
}

TEST_F(Samplers, ASamplerThatMissesPartOfTheLobeFails) {
  // Samples only the upper half of the cosine lobe's radius, with the matching density there:
  // every sample is consistent, but the estimate loses the missed directions (biased).
  auto r = renderer_->checkSampler(
      parse(lambertVariant("z / PI * 2.0", "BRDF(L, V, N, X, Y)",
                           "float r = sqrt(0.5 * u.x), phi = 2.0 * PI * u.y, z = sqrt(max(0.0, 1.0 - 0.5 * u.x));")));
  ASSERT_TRUE(r.ok());
  EXPECT_GT(r->maxAlbedoZ, 10.0);
  EXPECT_FALSE(r->passed());
}

TEST_F(Samplers, WithoutPdfBrdfTheChiSquareTestDoesNotRun) {
  auto r = renderer_->checkSampler(parse(lambertVariant("z / PI", "BRDF(L, V, N, X, Y)")));
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->chi2Run);
  EXPECT_TRUE(r->passed());
}

TEST_F(Samplers, ACorrectSamplerWithItsPdfPassesTheChiSquareTest) {
  auto r =
      renderer_->checkSampler(parse(lambertWithPdf(kCosineDraw, "pdfBRDF(L, V, N, X, Y)", "max(dot(N, L), 0.0) / PI")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(r->chi2Run);
  EXPECT_TRUE(r->chi2Failure.empty()) << r->chi2Failure;
  EXPECT_GE(r->minChi2PValue, r->chi2Threshold);
  // 0.01, Sidak-corrected over every (normal, view) configuration
  EXPECT_NEAR(r->chi2Threshold, 1.0 - std::pow(0.99, 1.0 / r->configurations), 1e-12);
  EXPECT_LT(r->maxPdfMismatch, 1e-6);
  EXPECT_TRUE(r->passed());
}

TEST_F(Samplers, ASamplerWhoseDrawsDoNotFollowItsPdfFailsTheChiSquareTest) {
  // Draws uniform directions but claims (and states in pdfBRDF) the cosine density: every
  // sample is consistent with pdfBRDF, only the histogram of the draws can tell.
  auto r = renderer_->checkSampler(
      parse(lambertWithPdf(kUniformDraw, "pdfBRDF(L, V, N, X, Y)", "max(dot(N, L), 0.0) / PI")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(r->chi2Run);
  EXPECT_LT(r->maxPdfMismatch, 1e-6);
  EXPECT_LT(r->minChi2PValue, 1e-12);
  EXPECT_FALSE(r->chi2Passed());
  EXPECT_FALSE(r->passed());
}

TEST_F(Samplers, AReturnedPdfThatIsNotPdfBrdfFails) {
  // pdfBRDF is right (the chi-square test passes), the pdf sampleBRDF returns is 10% high.
  auto r = renderer_->checkSampler(parse(lambertWithPdf(kCosineDraw, "1.1 * z / PI", "max(dot(N, L), 0.0) / PI")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(r->chi2Run);
  EXPECT_GE(r->minChi2PValue, r->chi2Threshold);
  EXPECT_NEAR(r->maxPdfMismatch, 0.1 / 1.1, 1e-3);
  EXPECT_FALSE(r->chi2Passed());
  EXPECT_FALSE(r->passed());
}

TEST_F(Samplers, SamplesWherePdfBrdfIsZeroFailTheChiSquareTest) {
  // pdfBRDF says nothing is drawn with phi < 0 (y < 0); the sampler draws there anyway.
  auto r = renderer_->checkSampler(
      parse(lambertWithPdf(kCosineDraw, "z / PI", "(L.z > 0.0 && L.y >= 0.0) ? 2.0 * L.z / PI : 0.0")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(r->chi2Run);
  EXPECT_EQ(r->minChi2PValue, 0.0);
  EXPECT_NE(r->chi2Failure.find("expected count is 0"), std::string::npos) << r->chi2Failure;
  EXPECT_FALSE(r->passed());
}

TEST_F(Samplers, TheCheckCoversNormalsNearEveryAxisAndViewsUpToGrazing) {
  auto r = renderer_->checkSampler(parse(lambertVariant("z / PI", "BRDF(L, V, N, X, Y)")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->configs.size(), r->configurations);
  ASSERT_GT(r->configurations, 0u);
  auto len = [](const Vec3& a) { return std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]); };
  auto dot = [](const Vec3& a, const Vec3& b) {
    return double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
  };
  // The first configurations are those of the original check: N = +z, X = +x, Y = +y.
  const SamplerCheckConfig& first = r->configs[0].config;
  EXPECT_EQ(first.normal, (Vec3{0, 0, 1}));
  EXPECT_EQ(first.tangent, (Vec3{1, 0, 0}));
  EXPECT_EQ(first.bitangent, (Vec3{0, 1, 0}));
  std::set<double> viewDegs, azimuths;
  int nearAxis[3][2] = {{0, 0}, {0, 0}, {0, 0}};  // per axis and sign: normals within (0, 2e-3] rad of it
  int arbitrary = 0;
  for (const SamplerConfigResult& c : r->configs) {
    const SamplerCheckConfig& k = c.config;
    EXPECT_NEAR(len(k.normal), 1.0, 1e-6);
    EXPECT_NEAR(len(k.tangent), 1.0, 1e-6);
    EXPECT_NEAR(len(k.bitangent), 1.0, 1e-6);
    EXPECT_NEAR(len(k.view), 1.0, 1e-6);
    EXPECT_NEAR(dot(k.normal, k.tangent), 0.0, 1e-6) << k.describe();
    EXPECT_NEAR(dot(k.normal, k.bitangent), 0.0, 1e-6) << k.describe();
    EXPECT_NEAR(dot(k.tangent, k.bitangent), 0.0, 1e-6) << k.describe();
    EXPECT_NEAR(dot(k.normal, k.view), std::cos(k.viewDeg * 3.14159265358979323846 / 180), 1e-6) << k.describe();
    viewDegs.insert(k.viewDeg);
    if (k.viewDeg > 0) azimuths.insert(k.viewAzimuthDeg);
    bool onAxis = false;
    for (int axis = 0; axis < 3; ++axis) {
      double a = std::acos(std::min(1.0, std::fabs(double(k.normal[axis]))));
      if (a < 1e-7) onAxis = true;
      if (a > 1e-4 && a <= 2e-3) ++nearAxis[axis][k.normal[axis] > 0 ? 0 : 1];
      if (a < 0.1) onAxis = true;
    }
    if (!onAxis) ++arbitrary;
  }
  for (double deg : {0.0, 30.0, 60.0, 80.0, 89.0}) EXPECT_EQ(viewDegs.count(deg), 1u) << deg;
  EXPECT_GE(azimuths.size(), 4u);
  for (int axis = 0; axis < 3; ++axis)
    for (int sign = 0; sign < 2; ++sign) EXPECT_GE(nearAxis[axis][sign], 5) << "axis " << axis << " sign " << sign;
  EXPECT_GE(arbitrary, 10);
  // Sidak over every configuration, and the worst one named.
  EXPECT_TRUE(r->passed()) << r->worst;
  EXPECT_LT(r->worstSeverity, 1.0);
  EXPECT_FALSE(r->worst.empty());
  EXPECT_LT(r->worstConfig, r->configs.size());
}

TEST_F(Samplers, DirectionsThatAreNotUnitLengthFail) {
  // Cosine draws with z 0.05% too long: the density is nearly right, the length is not.
  auto r = renderer_->checkSampler(
      parse(lambertVariant("z / PI", "BRDF(L, V, N, X, Y)",
                           "float r = sqrt(u.x), phi = 2.0 * PI * u.y, z = 1.0005 * sqrt(max(0.0, 1.0 - u.x));")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_GT(r->maxLengthError, 4e-4);
  EXPECT_LT(r->maxLengthError, 6e-4);
  EXPECT_FALSE(r->passed());
  EXPECT_EQ(r->worstCheck, "length") << r->worst;
  EXPECT_NE(r->worst.find("length"), std::string::npos) << r->worst;
}

TEST_F(Samplers, APositivePdfBelowTheHorizonFails) {
  // Uniform over the whole sphere with its pdf 1 / (4 pi): half the draws are below the
  // horizon with pdf > 0 (a sampler must reject them with pdf 0).
  auto r = renderer_->checkSampler(
      parse(lambertVariant("1.0 / (4.0 * PI)", "BRDF(L, V, N, X, Y)",
                           "float z = 1.0 - 2.0 * u.x, r = sqrt(max(0.0, 1.0 - z * z)), phi = 2.0 * PI * u.y;")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_GT(r->pdfBelowHorizon, r->samples / 4);
  EXPECT_FALSE(r->passed());
}

// The GGX sampler before its fix built its frame with the fallback tangent +x wherever
// |N.z| >= 0.999: fine at N = +z exactly (the original check's only normal), wrong within 2.6
// degrees of +-z. The extended check fails it there, and passes the fixed file.
TEST_F(Samplers, TheOldGgxFrameFailsNearTheZAxisAndTheFixedOnePasses) {
  auto old = renderer_->checkSampler(parse(testdata::kOldGgxBrdf));
  ASSERT_TRUE(old.ok()) << old.error().message;
  EXPECT_FALSE(old->passed());
  ASSERT_LT(old->worstConfig, old->configs.size());
  const SamplerConfigResult& worst = old->configs[old->worstConfig];
  EXPECT_GE(std::fabs(worst.config.normal[2]), 0.999f) << old->worst;  // inside the fallback branch
  EXPECT_GE(worst.worstSeverity, 1.0);
  EXPECT_GT(old->maxLengthError, 1e-4);
  std::cout << "[ old ggx  ] worst: " << old->worst << "\n";
  int failing = 0;
  for (const SamplerConfigResult& c : old->configs) {
    const bool fallback = std::fabs(c.config.normal[2]) >= 0.999f && std::fabs(c.config.normal[2]) < 1.0f;
    if (c.worstSeverity >= 1.0) {
      ++failing;
      // Every failure is where the fallback frame is not orthonormal ...
      EXPECT_TRUE(fallback) << c.config.describe() << ": " << c.worstCheck << " " << c.worstValue;
      std::cout << "[ old ggx  ] fails at " << c.config.describe() << ": " << c.worstCheck << " " << c.worstValue
                << "\n";
    }
    // ... so at N = +z, all the old check looked at, it passed.
    if (c.config.normal == Vec3{0, 0, 1}) {
      EXPECT_LT(c.worstSeverity, 1.0) << c.config.describe() << ": " << c.worstCheck << " " << c.worstValue;
    }
  }
  EXPECT_GE(failing, 3);

  auto fixed = renderer_->checkSampler(parse(readText(std::string(BRDFA_SOURCE_DIR) + "/shaders/brdfs/ggx.brdf")));
  ASSERT_TRUE(fixed.ok()) << fixed.error().message;
  EXPECT_TRUE(fixed->passed()) << fixed->worst;
  EXPECT_LT(fixed->maxLengthError, 1e-5);
}

TEST_F(Samplers, RenderingWithTheGgxSamplerIsUnbiasedAndLessNoisy) {
  BrdfDefinition ggx = parse(readText(std::string(BRDFA_SOURCE_DIR) + "/shaders/brdfs/ggx.brdf"));
  float roughness = 0.2f;
  auto render = [&](SamplingMode mode, const std::string& env, int spp) {
    Scene s;
    s.environment.name = env;
    s.environment.visible = false;
    s.render.width = s.render.height = 48;
    s.render.samplesPerFrame = 16;
    s.render.maxSamples = spp;
    s.render.sampling = mode;
    SceneObject o;
    o.brdf = std::make_shared<BrdfDefinition>(ggx);
    o.params["roughness"] = {roughness, 0, 0};
    o.params["F0"] = {1, 1, 1};
    s.objects.push_back(o);
    auto view = renderer_->createView().value();
    EXPECT_TRUE(view->setScene(s).ok());
    while (!view->renderPass()->done()) {
    }
    return view->readFrame(true).value();
  };
  // Furnace, normal incidence: E(mu=1) of GGX at alpha 0.2 from both samplers.
  Frame cosine = render(SamplingMode::Cosine, "furnace", 2048);
  Frame brdf = render(SamplingMode::Brdf, "furnace", 256);
  double c = 0, b = 0;
  for (int y = 22; y < 26; ++y)
    for (int x = 22; x < 26; ++x) {
      c += cosine.rgba32f[4 * (y * 48 + x)] / 16;
      b += brdf.rgba32f[4 * (y * 48 + x)] / 16;
    }
  EXPECT_NEAR(b, c, 0.01);
  EXPECT_EQ(brdf.stats.nanSamples, 0u);
  // A narrow lobe in the sky: hemisphere sampling rarely finds it, the BRDF's sampler always
  // does, so the error at equal samples must drop. (A wide lobe gains less here: what is left
  // is hits on the small, bright sun, which needs environment sampling.)
  roughness = 0.05f;
  Frame skyCosine = render(SamplingMode::Cosine, "sky", 64);
  Frame skyBrdf = render(SamplingMode::Brdf, "sky", 64);
  ASSERT_TRUE(skyCosine.stats.relError && skyBrdf.stats.relError);
  EXPECT_LT(*skyBrdf.stats.relError, *skyCosine.stats.relError / 2);
}

}  // namespace
}  // namespace brdfa
