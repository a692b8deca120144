// The fit job over HTTP (POST /api/jobs/fit): GGX fitted to a generated measured GGX recovers its
// roughness and F0, Beckmann (cook_torrance) fitted to it converges with a larger residual, an
// analytic target with the relative loss and a single variable, bad requests, cancellation.
#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <thread>

#include "brdfa/brdf.h"
#include "merl_files.h"
#include "server_fixture.h"

namespace brdfa::itest {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

// Generous: the sanitizer build evaluates several times slower.
const std::chrono::seconds kFitTimeout = kSanitizedBuild ? 900s : 300s;

class Fit : public ServerTest {
 protected:
  // Starts a fit; its job id ("" after a failed expectation).
  static std::string startFit(const json& body) {
    auto r = post("/api/jobs/fit", body.dump());
    EXPECT_TRUE(r && r->status == 202) << (r ? r->body : "no answer");
    return r ? bodyJson(r).value("id", "") : "";
  }
  // Runs a fit to the end and returns its result (null after a failed expectation).
  static json fitResult(const json& body) {
    const std::string id = startFit(body);
    if (id.empty()) return nullptr;
    json job = waitForJob(id, kFitTimeout);
    EXPECT_EQ(job.value("state", ""), "done") << job.dump().substr(0, 2000);
    return job.value("result", json());
  }
  static std::string uploadMeasured(const std::string& bytes) {
    httplib::MultipartFormDataItems items = {{"file", bytes, "ggx.binary", "application/octet-stream"},
                                             {"kind", "measured", "", ""}};
    auto r = server_->client(60)->Post("/api/assets", items);
    EXPECT_TRUE(r && r->status == 201) << (r ? r->body : "no answer");
    return r ? bodyJson(r).value("id", "") : "";
  }
};

// The width and height in a PNG's IHDR (0, 0 when it is not a PNG).
std::pair<uint32_t, uint32_t> pngSize(const std::string& png) {
  if (png.size() < 24 || png.compare(1, 3, "PNG") != 0) return {0, 0};
  auto be32 = [&](size_t at) {
    uint32_t v = 0;
    for (size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(png[at + i]);
    return v;
  };
  return {be32(16), be32(20)};
}

std::string base64Decode(const std::string& text) {
  static const std::string kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  uint32_t acc = 0;
  int bits = 0;
  for (char c : text) {
    const size_t v = kAlphabet.find(c);
    if (v == std::string::npos) continue;  // padding
    acc = (acc << 6) | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(char((acc >> bits) & 0xff));
    }
  }
  return out;
}

void expectWithin(double value, double truth, double relative, const std::string& what) {
  EXPECT_LE(std::fabs(value - truth), relative * std::fabs(truth)) << what << " = " << value << ", truth " << truth;
}

// The loss curve is the evaluations' losses with the best so far never rising.
void expectCurve(const json& result, int maxEvaluations) {
  const json& curve = result["loss_curve"];
  ASSERT_TRUE(curve.is_array() && !curve.empty());
  EXPECT_LE(curve.size(), 512u);
  EXPECT_LE(result["evaluations"].get<int>(), maxEvaluations);
  double best = HUGE_VAL;
  for (const json& p : curve) {
    EXPECT_LE(p["best"].get<double>(), best * (1 + 1e-12));
    EXPECT_GE(p["loss"].get<double>(), p["best"].get<double>() * (1 - 1e-12));
    best = p["best"].get<double>();
  }
  EXPECT_DOUBLE_EQ(best, result["final_loss"].get<double>());
  EXPECT_LE(result["final_loss"].get<double>(), result["initial_loss"].get<double>());
}

// The residual slice: 90 x 90 bins, the ones below the horizon left out, max_abs their largest
// magnitude, and the PNG that draws them.
void expectResidual(const json& residual) {
  ASSERT_TRUE(residual.is_object());
  const json& values = residual["values"];
  ASSERT_EQ(values.size(), 90u * 90u);
  size_t numbers = 0;
  double maxAbs = 0;
  for (const json& v : values)
    if (v.is_number()) {
      ++numbers;
      maxAbs = std::max(maxAbs, std::fabs(v.get<double>()));
    }
  EXPECT_GT(numbers, 4000u);
  EXPECT_LT(numbers, 90u * 90u) << "bins with L or V below the horizon have no residual";
  // Bin (theta_h 89, theta_d 89): both directions far below the horizon.
  EXPECT_TRUE(values[89 * 90 + 89].is_null());
  EXPECT_TRUE(values[0].is_number());  // theta_h = theta_d = 0: L = V = N
  EXPECT_NEAR(residual["max_abs"].get<double>(), maxAbs, 1e-12 + 1e-9 * maxAbs);
  const std::string png = residual["png"].get<std::string>();
  const std::string prefix = "data:image/png;base64,";
  ASSERT_EQ(png.compare(0, prefix.size(), prefix), 0);
  EXPECT_EQ(pngSize(base64Decode(png.substr(prefix.size()))), std::make_pair(90u, 90u));
}

TEST_F(Fit, GgxRecoversAMeasuredGgxAndBeckmannFitsItWorse) {
  const double alpha = 0.2;
  const testsupport::Rgb f0{0.8, 0.5, 0.3};
  const std::string id = uploadMeasured(testsupport::ggxMerl(alpha, f0));
  ASSERT_FALSE(id.empty());

  // From ggx.brdf's defaults (roughness 0.3, F0 0.95 0.64 0.54), not from the truth.
  const json ggxBody{{"model", {{"brdf", "ggx"}, {"fit", {{"roughness", nullptr}, {"F0", nullptr}}}}},
                     {"target", {{"brdf", id}}},
                     {"restarts", 2},
                     {"max_evaluations", 400}};
  json ggx = fitResult(ggxBody);
  ASSERT_TRUE(ggx.is_object());
  expectWithin(ggx["params"]["roughness"].get<double>(), alpha, 0.01, "roughness");
  for (int c = 0; c < 3; ++c) expectWithin(ggx["params"]["F0"][c].get<double>(), f0[c], 0.01, "F0");
  EXPECT_LT(ggx["final_loss"].get<double>(), 1e-8);
  EXPECT_GT(ggx["bins"].get<int>(), 10000);
  EXPECT_EQ(ggx["fitted"].get<std::set<std::string>>(), (std::set<std::string>{"roughness", "F0"}));
  EXPECT_EQ(ggx["restarts"].size(), 2u);
  expectCurve(ggx, 400);
  expectResidual(ggx["residual"]);

  // The preset saves as is, and the .brdf source carries the fitted values as its defaults.
  const json& preset = ggx["preset"];
  EXPECT_EQ(preset["brdf"], "ggx");
  EXPECT_EQ(preset["values"], ggx["params"]);
  auto saved = put("/api/brdfs/ggx/presets/" + preset["name"].get<std::string>(), preset["values"].dump());
  ASSERT_TRUE(saved && (saved->status == 201 || saved->status == 200)) << (saved ? saved->body : "no answer");
  Result<BrdfDefinition> source = parseBrdf(ggx["brdf_source"].get<std::string>());
  ASSERT_TRUE(source.ok());
  expectWithin(source.value().findParam("roughness")->defaultValue[0], ggx["params"]["roughness"], 1e-5,
               "the source's roughness");
  for (int c = 0; c < 3; ++c)
    expectWithin(source.value().findParam("F0")->defaultValue[c], ggx["params"]["F0"][c], 1e-5, "the source's F0");

  // Beckmann microfacets cannot take GGX's long tail: the fit converges to a larger residual.
  // cook_torrance's dielectric Fresnel (ior 1.5) reflects 4 % at normal incidence: Ks scales it.
  const json beckmannBody{{"model", {{"brdf", "cook_torrance"}, {"fit", {{"m", nullptr}, {"Ks", json{0, 25}}}}}},
                          {"target", {{"brdf", id}}},
                          {"restarts", 2},
                          {"max_evaluations", 300}};
  json beckmann = fitResult(beckmannBody);
  ASSERT_TRUE(beckmann.is_object());
  expectCurve(beckmann, 300);
  expectResidual(beckmann["residual"]);
  // Converged: both restarts, from different starts, reach the same minimum.
  ASSERT_EQ(beckmann["restarts"].size(), 2u);
  const double loss0 = beckmann["restarts"][0]["loss"].get<double>(),
               loss1 = beckmann["restarts"][1]["loss"].get<double>();
  EXPECT_NEAR(loss0, loss1, 0.02 * std::max(loss0, loss1)) << beckmann["restarts"].dump();
  EXPECT_LT(beckmann["final_loss"].get<double>(), beckmann["initial_loss"].get<double>());
  EXPECT_GT(beckmann["final_loss"].get<double>(), 100 * ggx["final_loss"].get<double>());
  EXPECT_GT(beckmann["residual"]["max_abs"].get<double>(), 10 * ggx["residual"]["max_abs"].get<double>());
  del("/api/assets/" + id);
}

TEST_F(Fit, AnAnalyticTargetFitsOneVariableWithTheRelativeLoss) {
  const json body{
      {"model", {{"brdf", "ggx"}, {"fit", {{"roughness", json{0.05, 1}}}}, {"params", {{"F0", {0.6, 0.6, 0.6}}}}}},
      {"target", {{"brdf", "ggx"}, {"params", {{"roughness", 0.5}, {"F0", {0.6, 0.6, 0.6}}}}}},
      {"loss", "relative"},
      {"restarts", 1},
      {"max_evaluations", 120}};
  json r = fitResult(body);
  ASSERT_TRUE(r.is_object());
  EXPECT_EQ(r["loss"], "relative");
  expectWithin(r["params"]["roughness"].get<double>(), 0.5, 0.01, "roughness");
  EXPECT_EQ(r["params"]["F0"], json({0.6, 0.6, 0.6}));  // fixed, as given
  expectCurve(r, 120);
  EXPECT_LT(r["final_loss"].get<double>(), 1e-8);
}

TEST_F(Fit, BadRequestsNameTheFieldAndLeaveTheServerWorking) {
  const json model{{"brdf", "ggx"}, {"fit", {{"roughness", nullptr}}}};
  const json target{{"brdf", "lambert"}};
  struct Case {
    json body;
    int status;
    std::string field;
  };
  const Case cases[] = {
      {json::array(), 400, ""},
      {{{"model", model}, {"target", target}, {"colour", 1}}, 400, "colour"},
      {{{"target", target}}, 400, "model"},
      {{{"model", model}}, 400, "target"},
      {{{"model", {{"brdf", "ggx"}}}, {"target", target}}, 400, "model.fit"},
      {{{"model", {{"brdf", "ggx"}, {"fit", {{"shininess", nullptr}}}}}, {"target", target}},
       400,
       "model.fit.shininess"},
      {{{"model", {{"brdf", "phong"}, {"fit", {{"divideByNoL", nullptr}}}}}, {"target", target}},
       400,
       "model.fit.divideByNoL"},
      {{{"model", {{"brdf", "ggx"}, {"fit", {{"roughness", json{0.5, 2}}}}}}, {"target", target}},
       400,
       "model.fit.roughness"},
      {{{"model", {{"brdf", "ggx"}, {"fit", {{"roughness", json{0.5, 0.5}}}}}}, {"target", target}},
       400,
       "model.fit.roughness"},
      {{{"model", {{"brdf", "ggx"}, {"fit", {{"F0", "all"}}}}}, {"target", target}}, 400, "model.fit.F0"},
      {{{"model", {{"brdf", "no_such_brdf"}, {"fit", {{"x", nullptr}}}}}, {"target", target}}, 404, "model.brdf"},
      {{{"model", model}, {"target", {{"brdf", "merl_00000000deadbeef"}}}}, 404, "target.brdf"},
      {{{"model", model}, {"target", {{"brdf", "lambert"}, {"params", {{"Kd", "white"}}}}}}, 400, "target.params.Kd"},
      {{{"model", model}, {"target", target}, {"loss", "l1"}}, 400, "loss"},
      {{{"model", model}, {"target", target}, {"restarts", 0}}, 400, "restarts"},
      {{{"model", model}, {"target", target}, {"restarts", 2.5}}, 400, "restarts"},
      {{{"model", model}, {"target", target}, {"max_evaluations", 5}}, 400, "max_evaluations"},
      {{{"model", model}, {"target", target}, {"max_evaluations", 1e9}}, 400, "max_evaluations"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.body.dump());
    expectError(post("/api/jobs/fit", c.body.dump()), c.status, c.field);
  }
  auto notJson = post("/api/jobs/fit", "{\"model\": ");
  ASSERT_TRUE(notJson);
  EXPECT_EQ(notJson->status, 400);
  auto health = get("/api/health");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
}

TEST_F(Fit, ACancelledFitStopsAfterShowingItsLossSoFar) {
  const json body{{"model", {{"brdf", "cook_torrance"}, {"fit", {{"m", nullptr}, {"ior", nullptr}, {"Ks", nullptr}}}}},
                  {"target", {{"brdf", "ggx"}}},
                  {"restarts", 16},
                  {"max_evaluations", 20000}};
  const std::string id = startFit(body);
  ASSERT_FALSE(id.empty());
  json job;
  for (auto deadline = std::chrono::steady_clock::now() + kFitTimeout; std::chrono::steady_clock::now() < deadline;) {
    job = bodyJson(get("/api/jobs/" + id));
    const std::string state = job.value("state", "");
    if (job.contains("partial") || (state != "queued" && state != "running")) break;
    std::this_thread::sleep_for(100ms);
  }
  ASSERT_EQ(job.value("state", ""), "running") << job.dump().substr(0, 2000);
  ASSERT_TRUE(job["partial"]["loss_curve"].is_array()) << job.dump().substr(0, 2000);
  EXPECT_FALSE(job["partial"]["loss_curve"].empty());
  EXPECT_GT(job["progress"].get<double>(), 0.0);
  auto cancelled = del("/api/jobs/" + id);
  ASSERT_TRUE(cancelled && cancelled->status == 200);
  job = waitForJob(id, 60s);
  EXPECT_EQ(job["state"], "cancelled");
  EXPECT_FALSE(job.contains("result"));
  EXPECT_FALSE(job.contains("partial"));
}

}  // namespace
}  // namespace brdfa::itest
