// Physics and behaviour of the renderer on the real Vulkan device (lavapipe here).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "brdfa/renderer.h"

#include "device_test.h"

namespace brdfa {
namespace {

class RendererPhysics : public DeviceTest {
 protected:
  static Scene furnaceScene(std::shared_ptr<const BrdfDefinition> brdf, int size, int spp) {
    Scene s;
    s.environment.name = "furnace";
    s.environment.visible = false;
    s.render.width = s.render.height = size;
    s.render.samplesPerFrame = 16;
    s.render.maxSamples = spp;
    SceneObject o;
    o.brdf = std::move(brdf);
    s.objects.push_back(o);
    return s;
  }

  static Frame renderToConvergence(RenderView& view) { return renderUntilDone(view); }

  // Colours of the pixels whose 3x3 neighbourhood is covered (away from the silhouette; the
  // hidden background is black).
  static std::vector<Vec3> interiorRgb(const Frame& f) {
    auto at = [&](int x, int y) { return &f.rgba32f[4 * (y * f.width + x)]; };
    auto covered = [&](int x, int y) { return at(x, y)[0] != 0.0f || at(x, y)[1] != 0.0f || at(x, y)[2] != 0.0f; };
    std::vector<Vec3> out;
    for (int y = 1; y + 1 < f.height; ++y)
      for (int x = 1; x + 1 < f.width; ++x) {
        bool inside = true;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) inside = inside && covered(x + dx, y + dy);
        if (inside) out.push_back(Vec3{at(x, y)[0], at(x, y)[1], at(x, y)[2]});
      }
    return out;
  }

  // The same pixels' red channel.
  static std::vector<float> interior(const Frame& f) {
    std::vector<float> out;
    for (const Vec3& v : interiorRgb(f)) out.push_back(v[0]);
    return out;
  }

  static double mean(const std::vector<float>& v) {
    double s = 0;
    for (float x : v) s += x;
    return v.empty() ? 0 : s / v.size();
  }

  // The interior pixels of a legacy render() file rendered in the hidden furnace.
  static std::vector<Vec3> legacyFurnacePixels(const std::string& text, int spp) {
    auto brdf = inlineBrdf(text);
    if (!brdf) return {};
    EXPECT_EQ(brdf->format, BrdfFormat::Legacy) << text;
    auto view = renderer_->createView().value();
    auto set = view->setScene(furnaceScene(brdf, 48, spp));
    EXPECT_TRUE(set.ok()) << text << ": " << (set.ok() ? "" : set.error().message);
    if (!set.ok()) return {};
    return interiorRgb(renderUntilDone(*view));
  }
};

TEST_F(RendererPhysics, WhiteLambertInFurnaceIsOneWithCosineSampling) {
  auto view = renderer_->createView().value();
  ASSERT_TRUE(view->setScene(furnaceScene(inlineBrdf(kWhiteLambert), 64, 32)).ok());
  Frame f = renderToConvergence(*view);
  auto px = interior(f);
  ASSERT_GT(px.size(), 500u);
  // Cosine sampling makes every sample exactly Kd * L: the estimate is 1 up to rounding.
  for (float v : px) ASSERT_NEAR(v, 1.0f, 1e-5f);
  EXPECT_EQ(f.rgba32f[0], 0.0f) << "hidden background must be black";
  EXPECT_EQ(f.stats.spp, 32u);
  EXPECT_TRUE(f.stats.maxSamplesReached);
}

TEST_F(RendererPhysics, WhiteLambertInFurnaceIsOneWithUniformSampling) {
  Scene s = furnaceScene(inlineBrdf(kWhiteLambert), 64, 256);
  s.render.sampling = SamplingMode::Uniform;
  auto view = renderer_->createView().value();
  ASSERT_TRUE(view->setScene(s).ok());
  Frame f = renderToConvergence(*view);
  auto px = interior(f);
  ASSERT_GT(px.size(), 500u);
  EXPECT_NEAR(mean(px), 1.0, 0.005);
  for (float v : px) ASSERT_NEAR(v, 1.0f, 0.05f);
  // Uniform sampling is noisy, so both halves differ; the estimate must say so.
  ASSERT_TRUE(f.stats.relError.has_value());
  EXPECT_GT(*f.stats.relError, 0.0);
}

// texCoord reaches the BRDF (the G-buffer's detail plane, fetched only for files that name it):
// a Lambertian with albedo (u, v, 0) in the furnace shows the sphere's UVs, exactly, with
// cosine sampling. The sphere's u = 0.5 + atan(z, x) / 2 pi faces the camera at the middle of
// each row and v runs from the top to the bottom, so a row through the centre spans u around
// 0.5 and a column v over most of 0..1 (0.18..0.82 away from the silhouette at 64^2).
TEST_F(RendererPhysics, TexCoordReachesTheBrdfAsTheMeshsUvs) {
  auto view = renderer_->createView().value();
  ASSERT_TRUE(view->setScene(furnaceScene(inlineBrdf(R"(analytic
::begin shader
const float PI = 3.14159265358979323846;
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(texCoord, 0.0) / PI; }
::end shader
)"),
                                          64, 16))
                  .ok());
  Frame f = renderToConvergence(*view);
  auto px = interiorRgb(f);
  ASSERT_GT(px.size(), 500u);
  float minU = 1, maxU = 0, minV = 1, maxV = 0;
  for (const Vec3& c : px) {
    ASSERT_GE(c[0], -1e-6f);
    ASSERT_LE(c[0], 1.0f + 1e-5f);
    ASSERT_EQ(c[2], 0.0f);
    minU = std::min(minU, c[0]), maxU = std::max(maxU, c[0]);
    minV = std::min(minV, c[1]), maxV = std::max(maxV, c[1]);
  }
  // Without texCoord every pixel would read (0, 0).
  EXPECT_GT(maxU - minU, 0.3f) << minU << ".." << maxU;
  EXPECT_GT(maxV - minV, 0.5f) << minV << ".." << maxV;
}

// Anti-aliasing: the visibility is rasterized at four sub-pixel positions across passes, so a
// silhouette pixel is the fraction of it the sphere covers. A white Lambert sphere in the
// furnace (exactly 1 where covered) against the hidden environment (0): the image sums to the
// sphere's projected area, and edge pixels take the values between.
TEST_F(RendererPhysics, SilhouettesAreAntiAliasedAndTheImageSumsToTheProjectedArea) {
  const int size = 128;
  Scene s = furnaceScene(inlineBrdf(kWhiteLambert), size, 64);
  s.render.samplesPerFrame = 4;
  auto view = renderer_->createView().value();
  ASSERT_TRUE(view->setScene(s).ok());
  Frame f = renderToConvergence(*view);
  // The unit sphere seen from distance 3 is a disc of angular radius asin(1/3) at the image
  // centre; its radius on the image plane in pixels:
  const double pi = 3.14159265358979323846;
  const double radius = std::tan(std::asin(1.0 / 3.0)) / std::tan(22.5 * pi / 180.0) * size / 2;
  double sum = 0;
  int partial = 0;
  for (int i = 0; i < size * size; ++i) {
    const float v = f.rgba32f[4 * i];
    ASSERT_GE(v, 0.0f);
    ASSERT_LE(v, 1.0f + 1e-5f);
    sum += v;
    if (v > 0.01f && v < 0.99f) ++partial;  // neither inside nor outside: an edge pixel
  }
  // Point sampling would also sum to about the area; only anti-aliasing gives edge pixels: the
  // edge crosses about 4/pi pixels per pixel of perimeter, and four sub-pixel positions see a
  // partial cover in most of them (measured: 262 of 343 perimeter pixels; point sampling: 0).
  EXPECT_NEAR(sum, pi * radius * radius, 0.005 * pi * radius * radius);
  EXPECT_GT(partial, 0.6 * 2.0 * pi * radius);
  EXPECT_LT(partial, 1.5 * 2.0 * pi * radius);
}

TEST_F(RendererPhysics, VisibleEnvironmentIsTheBackgroundAtItsIntensity) {
  Scene s = furnaceScene(inlineBrdf(kWhiteLambert), 32, 4);
  s.environment.visible = true;
  s.environment.intensity = 2.5f;
  auto view = renderer_->createView().value();
  ASSERT_TRUE(view->setScene(s).ok());
  Frame f = renderToConvergence(*view);
  EXPECT_FLOAT_EQ(f.rgba32f[0], 2.5f);                      // corner: background
  EXPECT_NEAR(f.rgba32f[4 * (16 * 32 + 16)], 2.5f, 1e-5f);  // centre: white sphere
}

// BRDFA Engine render() files run as that engine ran them: the plain average of render() over
// uniform hemisphere samples (docs/design.md section 3), reading `skybox`, iParameter0..8,
// iTexture0 and the world-to-local matrix.
TEST_F(RendererPhysics, LegacyRenderIsThePlainAverageOverTheHemisphere) {
  struct Case {
    const char* body;
    float expected;
    float tolerance;
  };
  const Case cases[] = {
      // skybox is the environment at intensity 1 (furnace: 1); iParameter0 defaults to 0.5.
      {"return texture(skybox, L).rgb * iParameter0 * 2.0;", 1.0f, 1e-5f},
      // The average of cos(theta) over uniform directions is 1/2: no cosine/pdf weighting.
      {"return vec3(dot(L, N));", 0.5f, 0.01f},
      // The engine's worldToLocal has N as its second row: it takes N to +y and L into the
      // upper hemisphere of y (LegacyWorldToLocalIsTheEnginesViewAlignedFrame pins all rows).
      {"vec3 l = worldToLocal * L; return vec3((worldToLocal * N).y * float(l.y >= 0.0));", 1.0f, 1e-5f},
      // An unbound texture reads as white.
      {"return texture(iTexture0, textureCord).rgb;", 1.0f, 1e-5f},
  };
  for (const Case& c : cases) {
    std::string text = std::string(
                           "#define PI 3.14159265359\n"
                           "vec3 render(vec3 L, vec3 N, vec3 V, vec2 textureCord, mat3 worldToLocal) {\n") +
                       c.body + "\n}\n";
    auto brdf = inlineBrdf(text);
    ASSERT_EQ(brdf->format, BrdfFormat::Legacy);
    Scene s = furnaceScene(brdf, 48, 256);
    s.render.sampling = SamplingMode::Brdf;  // ignored: a legacy file has one estimator
    auto view = renderer_->createView().value();
    auto set = view->setScene(s);
    ASSERT_TRUE(set.ok()) << c.body << ": " << set.error().message;
    Frame f = renderToConvergence(*view);
    auto px = interior(f);
    ASSERT_GT(px.size(), 300u) << c.body;
    EXPECT_NEAR(mean(px), c.expected, c.tolerance) << c.body;
  }
}

std::string engineStyleFile(const std::string& before, const std::string& body) {
  return before + "vec3 render(vec3 L, vec3 N, vec3 V, vec2 textureCord, mat3 worldToLocal){\n\t" + body + "\n}\n";
}

// A file in the engine's style may use the PI and LI of the engine's host shader
// without defining them (`#define PI 3.14159265359`, `#define LI 8.`), and renders as the engine
// rendered it: the plain average of render() over uniform directions.
TEST_F(RendererPhysics, LegacyFileUsingTheEnginesPiAndLiRendersAsTheEngineWould) {
  const double pi = 3.14159265358979323846;
  const struct {
    const char* body;
    int spp;
    double expected, tolerance;
  } cases[] = {
      // The engine's values themselves (a constant render() averages to itself).
      {"return vec3(PI);", 16, 3.14159265359, 1e-5},
      {"return vec3(LI);", 16, 8.0, 1e-5},
      // A Lambertian written as the engine's files are, in the furnace: the mean of
      // cos / PI over uniform directions, 1 / (2 pi) (no 2 pi for the uniform pdf), to 1%
      // (measured: 0.02%).
      {"return texture(skybox, L).rgb * max(dot(N, L), 0.) / PI;", 256, 1.0 / (2.0 * pi), 0.0016},
      // Lit at the engine's light intensity: LI / (2 pi) = 4 / pi, to 1%.
      {"return LI * texture(skybox, L).rgb * max(dot(N, L), 0.) / PI;", 256, 4.0 / pi, 0.0127},
  };
  for (const auto& c : cases) {
    std::vector<Vec3> px = legacyFurnacePixels(engineStyleFile("", c.body), c.spp);
    ASSERT_GT(px.size(), 300u) << c.body;
    double sum = 0;
    for (const Vec3& v : px) {
      EXPECT_EQ(v[0], v[1]) << c.body;
      EXPECT_EQ(v[0], v[2]) << c.body;
      sum += v[0];
    }
    EXPECT_NEAR(sum / px.size(), c.expected, c.tolerance) << c.body;
  }
}

// A file that gives PI or LI a meaning of its own (the engine rejected all but an identical
// #define) compiles and renders with its own value.
TEST_F(RendererPhysics, LegacyFileWithItsOwnPiOrLiUsesItsOwn) {
  const struct {
    const char* before;
    const char* body;
    float expected;
  } cases[] = {
      {"#define PI 3.14159265359\n", "return vec3(PI);", 3.14159265359f},
      {"#define PI 3.0\n", "return vec3(PI);", 3.0f},
      {"const float PI = 3.0;\n", "return vec3(PI);", 3.0f},
      {"#undef PI\nconst float PI = 2.5;\n", "return vec3(PI);", 2.5f},
      {"const float LI = 2.0;\n", "return vec3(LI + PI);", 2.0f + 3.14159265359f},
      {"", "float LI = 0.5; return vec3(LI * PI);", 0.5f * 3.14159265359f},
  };
  for (const auto& c : cases) {
    std::vector<Vec3> px = legacyFurnacePixels(engineStyleFile(c.before, c.body), 16);
    ASSERT_GT(px.size(), 300u) << c.before << c.body;
    for (const Vec3& v : px) ASSERT_NEAR(v[0], c.expected, 1e-5f) << c.before << c.body;
  }
}

// worldToLocal as the engine built it (shaders/kernels/shade.comp.glsl): rows T, N, B with
// T = normalize(cross(V, N)) and B = normalize(cross(T, N)), so N is its second row. Every pixel
// of the sphere has another normal, almost all of them off the axes.
TEST_F(RendererPhysics, LegacyWorldToLocalIsTheEnginesViewAlignedFrame) {
  // worldToLocal * N = (0, 1, 0): with rows X, Y, N it would be (0, 0, 1).
  std::vector<Vec3> px = legacyFurnacePixels(engineStyleFile("", "return 0.5 + 0.5 * (worldToLocal * N);"), 16);
  ASSERT_GT(px.size(), 300u);
  for (const Vec3& v : px) {
    ASSERT_NEAR(v[0], 0.5f, 1e-4f);
    ASSERT_NEAR(v[1], 1.0f, 1e-4f);
    ASSERT_NEAR(v[2], 0.5f, 1e-4f);
  }
  // The first and third rows: V goes to (0, N.V, -|V x N|) and V x N to (|V x N|, 0, 0). The
  // file returns 1 plus the residuals.
  px = legacyFurnacePixels(
      engineStyleFile("",
                      "vec3 c = cross(V, N);\n"
                      "\treturn vec3(1.0) + abs(worldToLocal * V - vec3(0.0, dot(N, V), -length(c)))\n"
                      "\t     + abs(worldToLocal * c - vec3(length(c), 0.0, 0.0));"),
      16);
  ASSERT_GT(px.size(), 300u);
  for (const Vec3& v : px)
    for (int i = 0; i < 3; ++i) ASSERT_NEAR(v[i], 1.0f, 1e-4f) << "channel " << i;
  // And the pixels' normals really vary: worldToLocal's first row, T, is not one fixed vector.
  px = legacyFurnacePixels(engineStyleFile("", "return 2.0 + transpose(worldToLocal)[0];"), 16);
  ASSERT_GT(px.size(), 300u);
  float lo = 10.0f, hi = -10.0f;
  for (const Vec3& v : px) lo = std::min(lo, v[0]), hi = std::max(hi, v[0]);
  EXPECT_GT(hi - lo, 0.5f);
}

// The sun's highlight on a sphere in image space: intensity-weighted centroid, and the
// principal axis (degrees, image x right, y down, modulo 180) and elongation (ratio of the
// standard deviations along and across it) of the pixels above 10% of the brightest.
struct Highlight {
  double cx = 0, cy = 0, angle = 0, elongation = 0;
};

Highlight highlightOf(const Frame& f) {
  float peak = 0;
  for (int i = 0; i < f.width * f.height; ++i) peak = std::max(peak, f.rgba32f[4 * i + 1]);
  double w = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x) {
      const double v = f.rgba32f[4 * (y * f.width + x) + 1];
      if (v < 0.1 * peak) continue;
      w += v;
      sx += v * x;
      sy += v * y;
      sxx += v * x * x;
      syy += v * y * y;
      sxy += v * x * y;
    }
  Highlight h;
  h.cx = sx / w;
  h.cy = sy / w;
  const double cxx = sxx / w - h.cx * h.cx, cyy = syy / w - h.cy * h.cy, cxy = sxy / w - h.cx * h.cy;
  h.angle = 0.5 * std::atan2(2 * cxy, cxx - cyy) * 180.0 / 3.14159265358979323846;
  const double mid = 0.5 * (cxx + cyy), d = std::sqrt(0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy);
  h.elongation = std::sqrt((mid + d) / std::max(mid - d, 1e-12));
  return h;
}

// Difference of two axis angles, modulo 180, in 0..90.
double axisDifference(double a, double b) {
  double d = std::fmod(std::fabs(a - b), 180.0);
  return d > 90.0 ? 180.0 - d : d;
}

// Ward with alpha_x (along the tangent) 10x alpha_y: the sun's highlight is a streak along the
// surface tangent, and turning the sphere a quarter turn about the view axis turns the streak
// with it (the highlight stays where the sun's half vector puts it). Isotropic Ward is round.
TEST_F(RendererPhysics, AnisotropicHighlightFollowsTheTangentAndTurnsWithTheObject) {
  const int size = 128;
  auto render = [&](float ax, float ay, float rotateZ) {
    Scene s;
    s.environment.name = "sky";
    s.environment.visible = false;
    s.render.width = s.render.height = size;
    s.render.samplesPerFrame = 64;
    s.render.maxSamples = 512;
    s.render.sampling = SamplingMode::Brdf;
    SceneObject o;
    o.brdf = builtin("ward");
    o.params = {{"rho_d", {0, 0, 0}}, {"rho_s", {1, 1, 1}}, {"alpha_x", {ax, 0, 0}}, {"alpha_y", {ay, 0, 0}}};
    o.rotate = {0, 0, rotateZ};
    s.objects.push_back(o);
    auto view = renderer_->createView().value();
    EXPECT_TRUE(view->setScene(s).ok());
    return highlightOf(renderToConvergence(*view));
  };
  const Highlight along = render(0.3f, 0.03f, 0), turned = render(0.3f, 0.03f, 90), round = render(0.1f, 0.1f, 0);
  std::printf("  highlight angle %.1f elongation %.2f; turned %.1f %.2f; isotropic %.2f\n", along.angle,
              along.elongation, turned.angle, turned.elongation, round.elongation);

  // The sphere's tangent (d/d longitude, horizontal in world) at the highlight, projected: the
  // camera at +3 z looks down -z, so a world direction (tx, ty, tz) at p moves the image point
  // along (tx + x_ndc tz, -(ty + y_ndc tz)) up to a positive factor (y down in the image).
  const double pi = 3.14159265358979323846, tanHalf = std::tan(22.5 * pi / 180.0);
  const double nx = (2.0 * (along.cx + 0.5) / size - 1.0) * tanHalf,
               ny = (1.0 - 2.0 * (along.cy + 0.5) / size) * tanHalf;
  // Ray from (0, 0, 3) along (nx, ny, -1) meets the unit sphere at p; tangent = (p.z, 0, -p.x).
  const double dd = nx * nx + ny * ny + 1, b = -3.0, c = 9.0 - 1.0;
  const double t = (-b - std::sqrt(b * b - dd * c)) / dd;
  const double px = nx * t, pz = 3.0 - t;
  const double tx = pz, tz = -px;
  const double tangentAngle = std::atan2(-(ny * tz), tx + nx * tz) * 180.0 / pi;  // ty = 0

  EXPECT_GT(along.elongation, 2.5);
  EXPECT_GT(turned.elongation, 2.5);
  EXPECT_LT(round.elongation, 1.6);
  EXPECT_LT(axisDifference(along.angle, tangentAngle), 15.0) << "tangent projects to " << tangentAngle;
  EXPECT_GT(axisDifference(along.angle, turned.angle), 70.0);
  // The highlight's place is set by the sun, not by the turn.
  EXPECT_NEAR(along.cx, turned.cx, 3.0);
  EXPECT_NEAR(along.cy, turned.cy, 3.0);
}

TEST_F(RendererPhysics, NanSamplesAreDroppedCountedAndNeverAccumulated) {
  // NaN for half of the hemisphere (L.x > 0), a white Lambertian elsewhere. The kept samples
  // still estimate the furnace exactly, so every pixel stays 1.
  auto nanBrdf = inlineBrdf(R"(analytic
::begin parameters
color Kd 1 1 1
::end parameters
::begin shader
const float PI = 3.14159265358979323846;
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {
    if (L.x > 0.0) return vec3(sqrt(-1.0 - L.y * L.y));
    return Kd / PI;
}
::end shader
)");
  auto view = renderer_->createView().value();
  ASSERT_TRUE(view->setScene(furnaceScene(nanBrdf, 48, 32)).ok());
  Frame f = renderToConvergence(*view);
  EXPECT_GT(f.stats.nanSamples, 1000u);
  for (float v : f.rgba32f) ASSERT_TRUE(std::isfinite(v));
  for (float v : interior(f)) ASSERT_NEAR(v, 1.0f, 1e-5f);
}

TEST_F(RendererPhysics, ParameterChangeRestartsWithoutRecompiling) {
  auto view = renderer_->createView().value();
  Scene s = furnaceScene(builtin("lambert"), 32, 8);
  s.objects[0].params["Kd"] = {1, 1, 1};
  ASSERT_TRUE(view->setScene(s).ok());
  Frame before = renderToConvergence(*view);
  const RendererCounters c0 = renderer_->counters();
  s.objects[0].params["Kd"] = {0.5f, 0.25f, 1.0f};
  ASSERT_TRUE(view->setScene(s).ok());
  EXPECT_EQ(view->stats().spp, 0u) << "a parameter change restarts accumulation";
  Frame after = renderToConvergence(*view);
  const RendererCounters c1 = renderer_->counters();
  EXPECT_EQ(c1.glslCompiles, c0.glslCompiles);
  EXPECT_EQ(c1.pipelinesCreated, c0.pipelinesCreated);
  const int centre = 4 * (16 * 32 + 16);
  EXPECT_NEAR(before.rgba32f[centre], 1.0f, 1e-5f);
  EXPECT_NEAR(after.rgba32f[centre + 0], 0.5f, 1e-5f);
  EXPECT_NEAR(after.rgba32f[centre + 1], 0.25f, 1e-5f);
  EXPECT_NEAR(after.rgba32f[centre + 2], 1.0f, 1e-5f);
}

TEST_F(RendererPhysics, ExposureChangeNeitherRestartsNorRecompiles) {
  auto view = renderer_->createView().value();
  Scene s = furnaceScene(builtin("lambert"), 32, 8);
  ASSERT_TRUE(view->setScene(s).ok());
  renderToConvergence(*view);
  const uint64_t version = view->stats().sceneVersion;
  s.render.exposure = 1.0f;
  ASSERT_TRUE(view->setScene(s).ok());
  EXPECT_EQ(view->stats().spp, 8u);
  EXPECT_GT(view->stats().sceneVersion, version);
}

TEST_F(RendererPhysics, GgxInFurnaceMatchesItsDirectionalAlbedo) {
  // White furnace, F = 1: a pixel shows the directional albedo E(mu) of single-scattering GGX,
  // which loses energy as roughness grows (Kulla and Conty 2017). E(1), normal incidence,
  // integrated independently on a 200k-point stratified grid of the same formulas.
  struct Case {
    float roughness;
    double albedo;
    double tolerance;
  };
  for (Case c :
       {Case{1.0f, 0.30685, 0.01}, Case{0.5f, 0.68785, 0.015}, Case{0.3f, 0.87736, 0.02}, Case{0.1f, 0.98830, 0.06}}) {
    Scene s = furnaceScene(builtin("ggx"), 48, 1024);
    s.objects[0].params["roughness"] = {c.roughness, 0, 0};
    s.objects[0].params["F0"] = {1, 1, 1};
    auto view = renderer_->createView().value();
    ASSERT_TRUE(view->setScene(s).ok());
    Frame f = renderToConvergence(*view);
    for (float v : f.rgba32f) ASSERT_TRUE(std::isfinite(v));
    EXPECT_EQ(f.stats.nanSamples, 0u);
    double centre = 0;  // 4x4 pixels around the centre of the sphere, where V is within 1 degree of N
    for (int y = 22; y < 26; ++y)
      for (int x = 22; x < 26; ++x) centre += f.rgba32f[4 * (y * 48 + x)] / 16.0;
    EXPECT_NEAR(centre, c.albedo, c.tolerance) << "roughness " << c.roughness;
    EXPECT_LE(mean(interior(f)), 1.0) << "energy gain at roughness " << c.roughness;
  }
}

TEST_F(RendererPhysics, RelativeErrorFallsAsSamplesAccumulate) {
  Scene s;
  s.environment.name = "sky";
  s.render.width = s.render.height = 64;
  s.render.samplesPerFrame = 4;
  s.render.maxSamples = 1024;
  SceneObject o;
  o.brdf = builtin("ggx");
  s.objects.push_back(o);
  auto view = renderer_->createView().value();
  ASSERT_TRUE(view->setScene(s).ok());
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(view->renderPass().ok());
  auto early = view->readFrame(false);
  ASSERT_TRUE(early.ok() && early->stats.relError.has_value());
  Frame late = renderToConvergence(*view);
  ASSERT_TRUE(late.stats.relError.has_value());
  EXPECT_LT(*late.stats.relError, *early->stats.relError / 4) << "16 spp -> 1024 spp";
}

TEST_F(RendererPhysics, CompileErrorLeavesThePreviousSceneInPlace) {
  auto view = renderer_->createView().value();
  ASSERT_TRUE(view->setScene(furnaceScene(builtin("lambert"), 32, 4)).ok());
  auto broken = inlineBrdf(
      "analytic\n::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return nope; }\n::end shader\n");
  auto r = view->setScene(furnaceScene(broken, 32, 4));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::CompileError);
  ASSERT_FALSE(r.error().diagnostics.empty());
  EXPECT_EQ(r.error().diagnostics[0].line, 3);
  EXPECT_TRUE(view->renderPass().ok());
}

TEST_F(RendererPhysics, UnknownNamesAndBadValuesAreErrorsNamingTheField) {
  auto view = renderer_->createView().value();
  Scene s = furnaceScene(builtin("lambert"), 32, 4);
  s.environment.name = "nowhere";
  auto r = view->setScene(s);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::NotFound);
  EXPECT_EQ(r.error().field, "environment.name");

  s = furnaceScene(builtin("lambert"), 32, 4);
  s.objects[0].params["Kd"] = {NAN, 0, 0};
  r = view->setScene(s);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().field, "objects[0].params.Kd");

  s = furnaceScene(builtin("lambert"), 8, 4);
  r = view->setScene(s);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().field, "render.width");
}

}  // namespace
}  // namespace brdfa
