// POST /api/analysis/{polar,lobe,albedo,slice} over HTTP against the real
// server: each plot checked against what the physics says it must be.
#include <cmath>
#include <sstream>

#include "ggx_albedo.h"
#include "server_fixture.h"

namespace brdfa::itest {
namespace {

using nlohmann::json;
constexpr double kPi = 3.14159265358979323846;

class Analysis : public ServerTest {
 protected:
  static json plot(const std::string& kind, const json& body, int expectStatus = 200) {
    auto r = post("/api/analysis/" + kind, body.dump());
    EXPECT_TRUE(r) << kind;
    if (!r) return json();
    EXPECT_EQ(r->status, expectStatus) << r->body;
    return bodyJson(r);
  }
  static double lum(const json& rgb) {
    return (rgb[0].get<double>() + rgb[1].get<double>() + rgb[2].get<double>()) / 3.0;
  }
};

// Lambert: f = Kd / pi everywhere above the horizon, in both planes; f cos = cos(theta) / pi.
TEST_F(Analysis, LambertPolarLobeIsFlatAtOneOverPi) {
  json out = plot("polar", {{"series", {{{"brdf", "lambert"}, {"params", {{"Kd", {1, 1, 1}}}}}}}, {"theta_i", 30}});
  ASSERT_EQ(out["axes"]["theta_deg"].size(), 181u);
  EXPECT_EQ(out["axes"]["theta_deg"].front(), -90.0);
  EXPECT_EQ(out["axes"]["theta_deg"].back(), 90.0);
  for (const char* plane : {"incidence", "perpendicular"}) {
    const json& values = out["series"][0]["values"][plane];
    ASSERT_EQ(values.size(), 181u) << plane;
    // Strictly above the horizon; at exactly +-90 degrees V is on it and the BRDF returns 0.
    for (size_t i = 1; i + 1 < values.size(); ++i)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(values[i][c].get<double>(), 1.0 / kPi, 1e-6) << plane << " " << i;
  }
  json cosine = plot(
      "polar",
      {{"series", {{{"brdf", "lambert"}, {"params", {{"Kd", {1, 1, 1}}}}}}}, {"theta_i", 30}, {"quantity", "f_cos"}});
  const json& theta = cosine["axes"]["theta_deg"];
  for (size_t i = 1; i + 1 < theta.size(); ++i)
    EXPECT_NEAR(lum(cosine["series"][0]["values"]["incidence"][i]), std::cos(theta[i].get<double>() * kPi / 180) / kPi,
                1e-6);
}

// GGX at theta_i = 30 degrees: the in-plane peak of a specular lobe is the mirror direction
// (+30 degrees on the far side), the perpendicular plane through it is symmetric and meets the
// incidence plane there. A rough lobe peaks off-specular, towards grazing (the 1 / (4 cos cos)
// and masking of Torrance and Sparrow 1967): the plot must show that too, not a mirror peak.
TEST_F(Analysis, GgxPolarPeaksAtTheMirrorAndThePerpendicularPlaneIsSymmetric) {
  for (double roughness : {0.02, 0.05, 0.1, 0.5}) {
    json out = plot("polar", {{"series", {{{"brdf", "ggx"}, {"params", {{"roughness", roughness}}}}}},
                              {"theta_i", 30},
                              {"resolution", 361}});
    const json& theta = out["axes"]["theta_deg"];
    ASSERT_EQ(theta[240], 30.0);
    const json& in = out["series"][0]["values"]["incidence"];
    size_t peak = 0;
    for (size_t i = 0; i < in.size(); ++i)
      if (lum(in[i]) > lum(in[peak])) peak = i;
    if (roughness <= 0.1) {
      EXPECT_NEAR(theta[peak].get<double>(), 30.0, 0.5) << "roughness " << roughness;  // one grid step
    } else {
      EXPECT_GT(theta[peak].get<double>(), 45.0) << "roughness " << roughness;  // off-specular
    }
    const json& perp = out["series"][0]["values"]["perpendicular"];
    const size_t n = perp.size();
    size_t perpPeak = 0;
    for (size_t i = 0; i < n; ++i) {
      EXPECT_NEAR(lum(perp[i]), lum(perp[n - 1 - i]), 1e-5 * std::max(1.0, lum(perp[i])))
          << "roughness " << roughness << " theta " << theta[i];
      if (lum(perp[i]) > lum(perp[perpPeak])) perpPeak = i;
    }
    if (roughness <= 0.1) {
      EXPECT_NEAR(theta[perpPeak].get<double>(), 0.0, 0.5);  // R itself
    }
    // The planes cross at R: the same value there.
    EXPECT_NEAR(lum(perp[n / 2]), lum(in[240]), 1e-4 * lum(in[240])) << "roughness " << roughness;
  }
}

// GGX's directional albedo (F0 = 1, so f = D G2 / (4 cos cos)) against an independent
// quadrature over the NDF's own CDF (tests/support/ggx_albedo.h), down to roughness 0.001,
// at views up to 89 degrees: within 1% or three of the endpoint's own standard errors.
TEST_F(Analysis, GgxAlbedoMatchesAnIndependentQuadratureDownToRoughness0001) {
  const std::vector<double> views = {0, 45, 80, 89};
  for (double roughness : {0.001, 0.01, 0.3, 1.0}) {
    json out =
        plot("albedo", {{"series", {{{"brdf", "ggx"}, {"params", {{"roughness", roughness}, {"F0", {1, 1, 1}}}}}}},
                        {"theta_v", views}});
    const json& s = out["series"][0];
    EXPECT_EQ(s["estimator"], "brdf sampler");
    ASSERT_EQ(s["values"].size(), views.size());
    for (size_t v = 0; v < views.size(); ++v) {
      const double mu = std::cos(views[v] * kPi / 180);
      const double truth = testsupport::ggxAlbedo(mu, roughness, 2048, 512);
      const double got = s["values"][v][0].get<double>(), err = s["std_error"][v][0].get<double>();
      EXPECT_LE(std::fabs(got - truth), std::max(0.01 * truth, 3.0 * err))
          << "roughness " << roughness << " view " << views[v] << ": " << got << " +- " << err << " vs " << truth;
      EXPECT_LE(got - 3.0 * err, 1.0);  // single scattering never gains energy
      std::printf("ggx roughness %-5g view %4g: albedo %.5f +- %.5f, quadrature %.5f\n", roughness, views[v], got, err,
                  truth);
    }
  }
}

// Without a sampler (a Lambert file of its own: the built-in has a cosine sampler, which is
// exact) the mixture estimator: Kd = 1 reflects everything, within the error bar it states.
TEST_F(Analysis, LambertAlbedoIsOneWithinItsErrorBar) {
  json out = plot("albedo", {{"series", {{{"source", kLambertWhite}}}}});
  const json& s = out["series"][0];
  EXPECT_EQ(s["estimator"], "cosine + half-vector mixture");
  ASSERT_EQ(out["axes"]["theta_v_deg"].size(), 19u);
  for (size_t v = 0; v < s["values"].size(); ++v) {
    const double got = s["values"][v][0].get<double>(), err = s["std_error"][v][0].get<double>();
    EXPECT_GT(err, 0.0);
    EXPECT_LT(err, 0.01);
    EXPECT_LE(std::fabs(got - 1.0), 4.0 * err) << "view " << out["axes"]["theta_v_deg"][v] << ": " << got;
  }
}

// The 3D lobe of lambert's f cos is cos(theta) / pi at every azimuth.
TEST_F(Analysis, LambertLobeIsTheCosine) {
  json out = plot("lobe", {{"series", {{{"brdf", "lambert"}, {"params", {{"Kd", {1, 1, 1}}}}}}},
                           {"theta_i", 45},
                           {"quantity", "f_cos"},
                           {"resolution", 10}});
  const json& theta = out["axes"]["theta_deg"];
  const json& phi = out["axes"]["phi_deg"];
  ASSERT_EQ(theta.size(), 10u);
  ASSERT_EQ(phi.size(), 36u);
  const json& rows = out["series"][0]["values"];
  ASSERT_EQ(rows.size(), phi.size());
  for (size_t p = 0; p < phi.size(); ++p)
    for (size_t t = 0; t + 1 < theta.size(); ++t)
      EXPECT_NEAR(lum(rows[p][t]), std::cos(theta[t].get<double>() * kPi / 180) / kPi, 1e-6);
}

// The image slice: f over (theta_h, theta_d); where L or V is below the horizon there is no
// value (null), exactly where the geometry says; lambert is 1/pi elsewhere. For GGX the
// specular peak is the theta_h = 0 column.
TEST_F(Analysis, SliceHasValuesExactlyAboveTheHorizon) {
  json out = plot("slice", {{"series", {{{"brdf", "lambert"}, {"params", {{"Kd", {1, 1, 1}}}}}, {{"brdf", "ggx"}}}},
                            {"resolution", 19},
                            {"phi_d", 90}});
  const json& th = out["axes"]["theta_h_deg"];
  const json& td = out["axes"]["theta_d_deg"];
  ASSERT_EQ(out["series"].size(), 2u);
  for (size_t d = 0; d < td.size(); ++d)
    for (size_t h = 0; h < th.size(); ++h) {
      // phi_d = 90: L and V are at cos(theta_h) cos(theta_d) above the horizon (Rusinkiewicz).
      const double z = std::cos(th[h].get<double>() * kPi / 180) * std::cos(td[d].get<double>() * kPi / 180);
      const json& v = out["series"][0]["values"][d][h];
      if (z > 1e-6) {
        EXPECT_NEAR(lum(v), 1.0 / kPi, 1e-6) << d << "," << h;
      } else {
        EXPECT_TRUE(v.is_null()) << d << "," << h;  // below or on the horizon: no value
      }
    }
  const json& ggx = out["series"][1]["values"];
  for (size_t d = 0; d + 1 < td.size(); ++d) {
    for (size_t h = 1; h < th.size(); ++h) {
      if (!ggx[d][h].is_null()) {
        EXPECT_GT(lum(ggx[d][0]), lum(ggx[d][h])) << d << "," << h;
      }
    }
  }
}

// Several series in one request (the thesis's D terms overlaid), labels kept, values clamped
// with a note, and the CSV form of the same data.
TEST_F(Analysis, OverlaysSeveralBrdfsAndWritesCsv) {
  json body = {{"series",
                {{{"brdf", "D_beckmann"}, {"params", {{"m", 0.3}}}, {"label", "Beckmann"}},
                 {{"brdf", "D_ggx"}, {"params", {{"alpha", 0.3}}}},
                 {{"brdf", "D_blinn"}, {"params", {{"n", 20.2}}}}}},
               {"theta_i", 20}};
  json out = plot("polar", body);
  ASSERT_EQ(out["series"].size(), 3u);
  EXPECT_EQ(out["series"][0]["label"], "Beckmann");
  EXPECT_EQ(out["series"][1]["label"], "D_ggx");
  EXPECT_EQ(out["series"][1]["params"]["alpha"], 0.3);
  // Equal peaks, 1 / (pi m^2) at the mirror direction (+20 degrees), different tails.
  EXPECT_NEAR(lum(out["series"][0]["values"]["incidence"][110]), 1.0 / (kPi * 0.09), 1e-4);
  EXPECT_NEAR(lum(out["series"][1]["values"]["incidence"][110]), 1.0 / (kPi * 0.09), 1e-4);
  EXPECT_GT(
      std::fabs(lum(out["series"][0]["values"]["incidence"][150]) - lum(out["series"][1]["values"]["incidence"][150])),
      0.01);

  json clamped = plot("polar", {{"series", {{{"brdf", "ggx"}, {"params", {{"roughness", 0}}}}}}});
  EXPECT_EQ(clamped["series"][0]["params"]["roughness"], 0.001);
  ASSERT_EQ(clamped["series"][0]["notes"].size(), 1u);
  EXPECT_NE(clamped["series"][0]["notes"][0].get<std::string>().find("clamped to 0.001"), std::string::npos);

  auto r = post("/api/analysis/polar?format=csv", body.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type").rfind("text/csv", 0), 0u);
  std::istringstream lines(r->body);
  std::string header, line;
  std::getline(lines, header);
  EXPECT_EQ(header, "series,label,plane,theta_deg,r,g,b");
  size_t rows = 0;
  while (std::getline(lines, line)) ++rows;
  EXPECT_EQ(rows, 3u * 2u * 181u);
  EXPECT_NE(r->body.find("0,\"Beckmann\",incidence,-90,"), std::string::npos);
}

// Bad requests get the right status and name the field; the server keeps working.
TEST_F(Analysis, BadRequestsAreRefusedWithTheirField) {
  auto expect = [](const std::string& kind, const json& body, int status, const std::string& field) {
    auto r = post("/api/analysis/" + kind, body.dump());
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, status) << kind << " " << body.dump() << " -> " << r->body;
    if (!field.empty()) {
      EXPECT_EQ(bodyJson(r)["field"], field) << r->body;
    }
  };
  const json lambert = {{{"brdf", "lambert"}}};
  expect("pie", {{"series", lambert}}, 404, "");
  expect("polar", json::object(), 400, "series");
  expect("polar", {{"series", json::array()}}, 400, "series");
  expect("polar",
         {{"series", json::array({lambert[0], lambert[0], lambert[0], lambert[0], lambert[0], lambert[0], lambert[0],
                                  lambert[0], lambert[0]})}},
         400, "series");
  expect("polar", {{"series", {{{"brdf", "nope"}}}}}, 404, "series[0].brdf");
  expect("polar", {{"series", {{{"brdf", "ggx"}, {"params", {{"shininess", 2}}}}}}}, 400, "series[0].params.shininess");
  expect("polar", {{"series", lambert}, {"theta_i", 95}}, 400, "theta_i");
  expect("polar", {{"series", lambert}, {"theta_i", "30"}}, 400, "theta_i");
  expect("polar", {{"series", lambert}, {"quantity", "g"}}, 400, "quantity");
  expect("lobe", {{"series", lambert}, {"resolution", 100000}}, 400, "resolution");
  expect("albedo", {{"series", lambert}, {"theta_v", {0, 90.5}}}, 400, "theta_v");
  expect("albedo", {{"series", lambert}, {"samples", 10}}, 400, "samples");
  expect("polar", {{"series", lambert}, {"colour", 1}}, 400, "colour");
  // A file that does not compile: 422 with the diagnostic's line.
  auto r = post("/api/analysis/polar", json{{"series",
                                             {{{"source",
                                                "::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n"
                                                "  return nope;\n}\n::end shader\n"}}}}}
                                           .dump());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 422) << r->body;
  EXPECT_EQ(bodyJson(r)["diagnostics"][0]["line"], 3) << r->body;
  // Still answering, with the right numbers.
  json out = plot("polar", {{"series", {{{"brdf", "lambert"}, {"params", {{"Kd", {1, 1, 1}}}}}}}});
  EXPECT_NEAR(lum(out["series"][0]["values"]["incidence"][90]), 1.0 / kPi, 1e-6);
}

// Side by side: two sessions under one camera and environment, their signed
// difference and its relative RMS with an error bar from both estimates.
class SideBySide : public ServerTest {
 protected:
  // The difference once both sessions have `spp` samples.
  static json difference(const std::string& a, const std::string& b, uint64_t spp) {
    for (const std::string& id : {a, b}) {
      auto f = get("/api/sessions/" + id + "/frame?format=pfm&min_spp=" + std::to_string(spp));
      EXPECT_TRUE(f && f->status == 200);
    }
    auto r = get("/api/sessions/" + a + "/difference?against=" + b + "&format=json");
    EXPECT_TRUE(r);
    if (!r) return json();
    EXPECT_EQ(r->status, 200) << r->body;
    return bodyJson(r);
  }
};

// In the furnace, Lambert's estimate with its cosine sampler is exact (zero variance): seen
// from close enough that the sphere fills the frame (no silhouette pixels, whose coverage is
// noisy), Kd 1 against Kd 0.5 differs by exactly half of A, with no error bar, and the PNG
// shows A brighter (red).
TEST_F(SideBySide, ExactImagesDifferByTheirAnalyticRatio) {
  auto scene = [](double kd, int seed) {
    json s = furnaceScene("lambert", {{"Kd", {kd, kd, kd}}}, 64, 8, 8);
    s["camera"] = {{"position", {0, 0, 1.2}}, {"fov", 45}};  // the sphere subtends 56 deg, the view 22.5
    s["render"]["seed"] = seed;
    return s;
  };
  const std::string a = createSession(scene(1.0, 1));
  const std::string b = createSession(scene(0.5, 2));
  json d = difference(a, b, 8);
  EXPECT_NEAR(d["rel_rms"].get<double>(), 0.5, 1e-4) << d.dump();
  EXPECT_LT(d["rel_rms_error"].get<double>(), 1e-4) << d.dump();
  EXPECT_EQ(d["pixels"], 64 * 64);  // every pixel is on the sphere
  auto png = get("/api/sessions/" + a + "/difference?against=" + b);
  ASSERT_TRUE(png);
  ASSERT_EQ(png->status, 200);
  EXPECT_EQ(png->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(png->get_header_value("X-Rel-RMS").substr(0, 3), "0.5");
  auto swapped = get("/api/sessions/" + b + "/difference?against=" + a + "&format=json");
  ASSERT_TRUE(swapped);
  EXPECT_NEAR(bodyJson(swapped)["rel_rms"].get<double>(), 1.0, 1e-4);  // against B's mean: 0.5 / 0.5
  for (const std::string& id : {a, b}) del("/api/sessions/" + id);
}

// Noisy estimates: the same GGX under the sky with two seeds differs only by noise, so the
// corrected figure is 0 within its error bar while the raw one is not; a real change of
// roughness stands far above it.
TEST_F(SideBySide, NoiseIsTakenOutAndARealDifferenceStandsAboveIt) {
  auto scene = [](double roughness, int seed) {
    json s = furnaceScene("ggx", {{"roughness", roughness}}, 64, 64, 16);
    s["environment"] = {{"name", "sky"}, {"visible", false}};
    s["render"]["seed"] = seed;
    return s;
  };
  const std::string a = createSession(scene(0.3, 1));
  const std::string same = createSession(scene(0.3, 2));
  const std::string other = createSession(scene(0.6, 3));
  json noise = difference(a, same, 64);
  const double sigma = noise["rel_rms_error"].get<double>();
  EXPECT_GT(sigma, 0.0) << noise.dump();
  EXPECT_LE(noise["rel_rms"].get<double>(), 3.0 * sigma) << noise.dump();
  EXPECT_GT(noise["raw_rel_rms"].get<double>(), noise["rel_rms"].get<double>()) << noise.dump();
  json real = difference(a, other, 64);
  EXPECT_GT(real["rel_rms"].get<double>(), 10.0 * real["rel_rms_error"].get<double>()) << real.dump();
  std::printf("same BRDF, two seeds: rel_rms %.4f +- %.4f (raw %.4f); roughness 0.3 vs 0.6: %.4f +- %.4f\n",
              noise["rel_rms"].get<double>(), sigma, noise["raw_rel_rms"].get<double>(), real["rel_rms"].get<double>(),
              real["rel_rms_error"].get<double>());
  // Errors: no such session, no against, bad format.
  EXPECT_EQ(get("/api/sessions/" + a + "/difference?against=nope")->status, 404);
  EXPECT_EQ(get("/api/sessions/" + a + "/difference")->status, 400);
  EXPECT_EQ(get("/api/sessions/" + a + "/difference?against=" + same + "&format=gif")->status, 400);
  for (const std::string& id : {a, same, other}) del("/api/sessions/" + id);
}

}  // namespace
}  // namespace brdfa::itest
