// BRDF importance samplers (`::begin sample`): every built-in one passes the sampler checks,
// broken ones fail them, and rendering with them is unbiased and less noisy.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "brdfa/renderer.h"

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
    EXPECT_TRUE(r->passed()) << entry.path().filename() << ": mismatch " << r->maxValueMismatch << ", cell z "
                             << r->maxCellZ << " over " << r->cellsTested << " cells, albedo z " << r->maxAlbedoZ;
    EXPECT_GT(r->cellsTested, 20u) << entry.path().filename();
  }
  EXPECT_GE(withSampler, 6);  // lambert, ggx, phong_normalized, blinn_phong_normalized, ward, cook_torrance
}

const char* kLambertWithSampler = R"(analytic
::begin parameters
color Kd 1 1 1
::end parameters
::begin shader
const float PI = 3.14159265358979323846;
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd / PI; }
::end shader
::begin sample
vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, out float pdf) {
    float r = sqrt(u.x), phi = 2.0 * PI * u.y, z = sqrt(max(0.0, 1.0 - u.x));
    L = X * (r * cos(phi)) + Y * (r * sin(phi)) + N * z;
    pdf = PDF_EXPR;
    return VALUE_EXPR;
}
::end sample
)";

std::string lambertVariant(const std::string& pdf, const std::string& value) {
  std::string s = kLambertWithSampler;
  s.replace(s.find("PDF_EXPR"), 8, pdf);
  s.replace(s.find("VALUE_EXPR"), 10, value);
  return s;
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
  EXPECT_GT(r->maxCellZ, 10.0);
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
  auto def = parse(lambertVariant("z / PI * 2.0", "BRDF(L, V, N, X, Y)").replace(
      std::string(kLambertWithSampler).find("float r = sqrt(u.x)"), 19, "float r = sqrt(0.5 * u.x)"));
  auto r = renderer_->checkSampler(def);
  ASSERT_TRUE(r.ok());
  EXPECT_GT(r->maxAlbedoZ, 10.0);
  EXPECT_FALSE(r->passed());
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
    while (!view->renderPass()->converged) {
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
