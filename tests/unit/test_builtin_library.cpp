// The built-in BRDF library (shaders/brdfs): every file parses, compiles, renders without NaN
// in the white furnace, and the models that claim energy conservation reflect at most the
// incident light at normal incidence, at their defaults and at parameter extremes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "brdfa/renderer.h"

#include "device_test.h"

namespace brdfa {
namespace {

namespace fs = std::filesystem;

const std::string kBrdfDir = std::string(BRDFA_SOURCE_DIR) + "/shaders/brdfs";

std::vector<std::string> libraryNames() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(kBrdfDir))
    if (e.path().extension() == ".brdf") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::shared_ptr<const BrdfDefinition> load(const std::string& name) { return builtin(name); }

using Params = std::map<std::string, Vec3>;

class BuiltinLibrary : public DeviceTest {
 protected:
  // Environment furnace (L_env = 1), hidden background, a sphere filling the view.
  static Frame furnace(std::shared_ptr<const BrdfDefinition> brdf, const Params& params, int size, int spp) {
    Scene s;
    s.environment.name = "furnace";
    s.environment.visible = false;
    s.render.width = s.render.height = size;
    s.render.samplesPerFrame = std::min(spp, kMaxSamplesPerFrame);
    s.render.maxSamples = spp;
    SceneObject o;
    o.brdf = std::move(brdf);
    o.params = params;
    s.objects.push_back(o);
    auto view = renderer_->createView();
    EXPECT_TRUE(view.ok());
    if (!view.ok()) return {};
    auto set = view.value()->setScene(s);
    EXPECT_TRUE(set.ok()) << (set.ok() ? "" : set.error().message);
    if (!set.ok()) return {};
    for (int guard = 0; guard < 1000; ++guard) {
      auto pass = view.value()->renderPass();
      EXPECT_TRUE(pass.ok());
      if (!pass.ok() || pass->done()) break;
    }
    auto frame = view.value()->readFrame(true);
    EXPECT_TRUE(frame.ok());
    return frame.ok() ? frame.value() : Frame{};
  }

  // Mean of the 4x4 centre pixels, all channels: there V is within a few degrees of N.
  static double centreMean(const Frame& f) {
    double sum = 0;
    int count = 0;
    for (int y = f.height / 2 - 2; y < f.height / 2 + 2; ++y)
      for (int x = f.width / 2 - 2; x < f.width / 2 + 2; ++x)
        for (int c = 0; c < 3; ++c, ++count) sum += f.rgba32f[4 * (y * f.width + x) + c];
    return count ? sum / count : 0;
  }
};

// Every model that must have a file (the library is at least this).
TEST_F(BuiltinLibrary, HasEveryModel) {
  const auto names = libraryNames();
  const std::set<std::string> have(names.begin(), names.end());
  for (const char* n : {"lambert",
                        "ggx",
                        "oren_nayar",
                        "disney_diffuse",
                        "phong",
                        "blinn_phong",
                        "phong_normalized",
                        "blinn_phong_normalized",
                        "lafortune",
                        "ward",
                        "ashikhmin_shirley",
                        "torrance_sparrow",
                        "cook_torrance",
                        "disney",
                        "D_beckmann",
                        "D_ggx",
                        "D_blinn",
                        "D_gaussian",
                        "G_implicit",
                        "G_cook_torrance",
                        "G_torrance_sparrow",
                        "G_smith_ggx",
                        "G_smith_beckmann",
                        "G_schlick_ggx",
                        "F_schlick",
                        "F_dielectric",
                        "F_conductor"})
    EXPECT_TRUE(have.count(n)) << n;
  for (const char* n : {"phong_normalized", "blinn_phong_normalized", "ward", "cook_torrance"}) {
    auto def = load(n);
    ASSERT_TRUE(def);
    EXPECT_TRUE(def->hasSampler()) << n << " must have a sample section";
  }
}

TEST_F(BuiltinLibrary, EveryFileParsesCompilesAndRendersWithoutNaN) {
  for (const auto& name : libraryNames()) {
    SCOPED_TRACE(name);
    auto def = load(name);
    ASSERT_TRUE(def);
    auto compiled = renderer_->compileBrdf(*def);
    ASSERT_TRUE(compiled.ok()) << compiled.error().message
                               << (compiled.error().diagnostics.empty()
                                       ? ""
                                       : ": " + compiled.error().diagnostics[0].message);
    Frame f = furnace(def, {}, 32, 64);
    ASSERT_EQ(f.rgba32f.size(), 32u * 32u * 4u);
    EXPECT_EQ(f.stats.nanSamples, 0u);
    for (float v : f.rgba32f) ASSERT_TRUE(std::isfinite(v));
    EXPECT_GT(centreMean(f), 0.0) << "default parameters should reflect something";
  }
}

TEST_F(BuiltinLibrary, WhiteLambertIsExactlyOne) {
  Frame f = furnace(load("lambert"), {{"Kd", {1, 1, 1}}}, 32, 16);
  EXPECT_NEAR(centreMean(f), 1.0, 1e-5);
}

// Models claiming energy conservation, at defaults and extreme settings (the white furnace
// shows the directional albedo). Cosine sampling, so narrow lobes are noisy: more samples.
TEST_F(BuiltinLibrary, EnergyConservingModelsReflectAtMostOne) {
  struct Case {
    const char* name;
    Params params;
  };
  const std::vector<Case> cases = {
      {"lambert", {}},
      {"ggx", {{"roughness", {1, 0, 0}}, {"F0", {1, 1, 1}}}},
      {"ggx", {{"roughness", {0.05f, 0, 0}}, {"F0", {1, 1, 1}}}},
      {"oren_nayar", {{"rho", {1, 1, 1}}}},
      {"oren_nayar", {{"sigma", {0, 0, 0}}, {"rho", {1, 1, 1}}}},
      {"oren_nayar", {{"sigma", {1, 0, 0}}, {"rho", {1, 1, 1}}}},
      {"phong_normalized", {}},
      {"phong_normalized", {{"n", {1, 0, 0}}}},
      {"phong_normalized", {{"n", {1000, 0, 0}}}},
      {"lafortune", {{"rho", {1, 1, 1}}}},
      {"lafortune", {{"rho", {1, 1, 1}}, {"n", {1, 0, 0}}}},
      {"lafortune", {{"rho", {1, 1, 1}}, {"n", {1, 0, 0}}, {"Cx", {1, 0, 0}}, {"Cy", {1, 0, 0}}}},
      {"lafortune", {{"rho", {1, 1, 1}}, {"n", {1000, 0, 0}}}},
      {"ward", {}},
      {"ward", {{"alpha_x", {0.5f, 0, 0}}, {"alpha_y", {0.5f, 0, 0}}}},
      {"ward", {{"alpha_x", {0.01f, 0, 0}}, {"alpha_y", {0.5f, 0, 0}}}},
      {"ward", {{"rho_d", {0.5f, 0.5f, 0.5f}}, {"rho_s", {0.5f, 0.5f, 0.5f}}}},
      {"ashikhmin_shirley", {{"Rd", {1, 1, 1}}}},
      {"ashikhmin_shirley", {{"Rd", {1, 1, 1}}, {"Rs", {0, 0, 0}}, {"nu", {1, 0, 0}}, {"nv", {1, 0, 0}}}},
      {"ashikhmin_shirley", {{"Rd", {0, 0, 0}}, {"Rs", {1, 1, 1}}, {"nu", {1, 0, 0}}, {"nv", {1, 0, 0}}}},
      {"ashikhmin_shirley", {{"Rd", {1, 1, 1}}, {"Rs", {1, 1, 1}}, {"nu", {1000, 0, 0}}, {"nv", {1, 0, 0}}}},
      {"torrance_sparrow", {{"ior", {3, 0, 0}}}},
      {"torrance_sparrow", {{"ior", {3, 0, 0}}, {"sigma", {0.6f, 0, 0}}}},
      {"torrance_sparrow", {{"ior", {3, 0, 0}}, {"sigma", {0.01f, 0, 0}}}},
      {"cook_torrance", {{"ior", {3, 0, 0}}}},
      {"cook_torrance", {{"ior", {3, 0, 0}}, {"m", {1, 0, 0}}}},
      {"cook_torrance", {{"ior", {3, 0, 0}}, {"m", {0.01f, 0, 0}}}},
  };
  for (const Case& c : cases) {
    std::string settings;
    for (const auto& [k, v] : c.params) settings += " " + k + "=" + std::to_string(v[0]);
    SCOPED_TRACE(std::string(c.name) + settings);
    // A lobe as narrow as exponent 1000 is hit by about one cosine sample in 500: 16x the
    // samples keep its estimate's noise (~7% at 1024 spp) well below the 1% margin.
    bool narrow = false;
    for (const auto& [k, v] : c.params) narrow = narrow || v[0] >= 1000.0f;
    Frame f = furnace(load(c.name), c.params, 32, narrow ? 16384 : 1024);
    EXPECT_EQ(f.stats.nanSamples, 0u);
    const double m = centreMean(f);
    EXPECT_LE(m, 1.01);
    std::printf("  %-24s%-60s albedo(centre) %.4f\n", c.name, settings.c_str(), m);
  }
}

// Every built-in is free of NaN, Inf and negative values over the device check's extreme grid
// (polar angles to 89.9 degrees and exactly 90, every parameter at its minimum and maximum),
// and reciprocal models are symmetric in L and V to 1e-4 relative. phong with
// divideByNoL = 1 (its default, as published) is not reciprocal.
TEST_F(BuiltinLibrary, NumericChecksAreCleanAndReciprocalModelsAreSymmetric) {
  for (const auto& name : libraryNames()) {
    SCOPED_TRACE(name);
    auto report = renderer_->checkBrdf(*load(name));
    ASSERT_TRUE(report.ok()) << report.error().message;
    EXPECT_TRUE(report->ok()) << "nan " << report->nanCount << " inf " << report->infCount << " negative "
                              << report->negativeCount;
    if (name != "phong") {
      EXPECT_LT(report->maxReciprocityError, 1e-4);
    }
  }
}

// (n+8)/(8 pi) is only an approximate Blinn-Phong normalization: the albedo at normal
// incidence is 1.024 at n = 1 (exact quadrature) and peaks at 1.075 near n = 8.
TEST_F(BuiltinLibrary, NormalizedBlinnPhongOvershootsOnlyAsDocumented) {
  for (float n : {1.0f, 8.0f, 1000.0f}) {
    Frame f = furnace(load("blinn_phong_normalized"), {{"n", {n, 0, 0}}}, 32, 1024);
    EXPECT_EQ(f.stats.nanSamples, 0u);
    EXPECT_LE(centreMean(f), 1.08) << "n " << n;
  }
}

}  // namespace
}  // namespace brdfa
