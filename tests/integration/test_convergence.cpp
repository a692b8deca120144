// Images that converge: render.target_error and render.sampling in scenes, the
// session's error-against-time series (GET .../convergence, JSON and CSV), stopping at a target
// error, and the strategy comparison job (POST /api/jobs/convergence).
// Until environment importance sampling lands, "environment" and "mis" render as cosine does:
// these tests check behaviour and shapes, never that one mode beats another.
#include <cmath>
#include <set>
#include <sstream>
#include <thread>

#include "server_fixture.h"

namespace brdfa::itest {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

constexpr int kMaxSamplesForever = 1 << 20;  // the renderer's limit: rendering runs on

// A Lambertian sphere in the sky (sun included), small so that passes are quick.
json skyLambert(const std::string& sampling, int size, int maxSamples, const json& targetError = nullptr,
                int samplesPerFrame = 4) {
  return {{"environment", {{"name", "sky"}}},
          {"objects", json::array({{{"mesh", "sphere"}, {"brdf", "lambert"}}})},
          {"render",
           {{"width", size},
            {"height", size},
            {"samples_per_frame", samplesPerFrame},
            {"max_samples", maxSamples},
            {"sampling", sampling},
            {"target_error", targetError}}}};
}

class Convergence : public ServerTest {
 protected:
  static json getJson(const std::string& path) {
    auto r = get(path);
    EXPECT_TRUE(r) << path;
    if (!r) return nullptr;
    EXPECT_EQ(r->status, 200) << path << ": " << r->body;
    return bodyJson(r);
  }
};

TEST_F(Convergence, SceneCarriesSamplingAndTargetError) {
  std::string sid = createSession(skyLambert("environment", 32, 16, 0.05));
  ASSERT_FALSE(sid.empty());
  const std::string path = "/api/sessions/" + sid + "/scene";
  json scene = getJson(path);
  EXPECT_EQ(scene["render"]["sampling"], "environment");
  EXPECT_EQ(scene["render"]["target_error"], 0.05);
  // Round trip: what GET answers, PUT takes back unchanged.
  auto r = put(path, scene.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(bodyJson(r), scene);
  // null clears the target; every sampling name is accepted.
  for (const char* mode : {"cosine", "uniform", "brdf", "environment", "mis"}) {
    r = patch(path, json{{"render", {{"sampling", mode}, {"target_error", nullptr}}}}.dump());
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << mode << ": " << r->body;
    EXPECT_EQ(bodyJson(r)["render"]["sampling"], mode);
    EXPECT_TRUE(bodyJson(r)["render"]["target_error"].is_null());
  }
  // Absent fields take the defaults: mis, no target.
  r = put(path, R"({"render": {"width": 32, "height": 32}})");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(bodyJson(r)["render"]["sampling"], "mis");
  EXPECT_TRUE(bodyJson(r)["render"]["target_error"].is_null());
  // Bad values name the field and change nothing.
  for (const char* bad : {"0", "1", "-0.1", "1.5", "\"0.1\"", "true", "[0.1]"})
    expectError(patch(path, std::string(R"({"render": {"target_error": )") + bad + "}}"), 400, "render.target_error");
  expectError(patch(path, R"({"render": {"sampling": "importance"}})"), 400, "render.sampling");
  EXPECT_EQ(getJson(path)["render"]["sampling"], "mis");
  json stats = getJson("/api/sessions/" + sid + "/stats");
  for (const char* key : {"converged", "max_samples_reached", "done", "target_error", "sampling", "estimator",
                          "warnings", "rel_error_spp", "rel_error_elapsed_ms"})
    EXPECT_TRUE(stats.contains(key)) << key << " in " << stats.dump();
  EXPECT_TRUE(stats["estimator"].is_string());
  EXPECT_TRUE(stats["warnings"].is_array());
  EXPECT_EQ(del("/api/sessions/" + sid)->status, 204);
}

TEST_F(Convergence, SeriesGrowsAndFallsAtAMonteCarloRate) {
  // One sample per pass: with more, the renderer's current half-accumulator estimate levels off
  // (about -0.2 at 4 per pass). The series and fit are the same either way.
  std::string sid = createSession(skyLambert("cosine", 64, kMaxSamplesForever, nullptr, 1));
  ASSERT_FALSE(sid.empty());
  const std::string base = "/api/sessions/" + sid + "/convergence";
  // Polling counts as watching: the session renders meanwhile.
  size_t lastCount = 0;
  uint64_t lastSpp = 0;
  int grew = 0;
  json c;
  for (auto end = Clock::now() + 4s; Clock::now() < end;) {
    std::this_thread::sleep_for(250ms);
    c = getJson(base);
    ASSERT_TRUE(c["points"].is_array()) << c.dump();
    EXPECT_GE(c["points"].size(), lastCount) << "the series only grows while the scene stays";
    grew += c["points"].size() > lastCount;
    lastCount = c["points"].size();
    EXPECT_GE(c["spp"].get<uint64_t>(), lastSpp);
    lastSpp = c["spp"].get<uint64_t>();
  }
  EXPECT_GE(grew, 3) << "points keep coming while it renders";
  ASSERT_GE(lastCount, 5u) << c.dump();
  const json& points = c["points"];
  for (size_t i = 1; i < points.size(); ++i) {
    EXPECT_GT(points[i]["spp"].get<uint64_t>(), points[i - 1]["spp"].get<uint64_t>());
    EXPECT_GT(points[i]["elapsed_ms"].get<double>(), points[i - 1]["elapsed_ms"].get<double>());
    EXPECT_GE(points[i]["passes"].get<uint64_t>(), points[i - 1]["passes"].get<uint64_t>());
  }
  EXPECT_EQ(c["sampling"], "cosine");
  EXPECT_TRUE(c["estimator"].is_string());
  EXPECT_TRUE(c["target_error"].is_null());
  EXPECT_TRUE(c["predicted_ms"].is_null()) << "no target, no prediction";
  ASSERT_TRUE(c["fit"].is_object()) << c.dump();
  const double slope = c["fit"]["slope"].get<double>();
  // 1/sqrt(N) is -0.5; the renderer's low-discrepancy samples make it steeper (about -0.7 here).
  EXPECT_LT(slope, -0.3) << c.dump();
  EXPECT_GT(slope, -1.2) << c.dump();
  EXPECT_GE(c["fit"]["points_used"].get<size_t>(), 3u);
  EXPECT_GE(c["fit"]["time_offset_ms"].get<double>(), 0.0);

  // A target predicts when the line reaches it: later than now for a target below the error.
  const double now = points.back()["elapsed_ms"].get<double>();
  const double err = points.back()["rel_error"].get<double>();
  json predicted = getJson(base + "?target=" + std::to_string(err / 4));
  ASSERT_TRUE(predicted["predicted_ms"].is_number()) << predicted.dump();
  EXPECT_GT(predicted["predicted_ms"].get<double>(), now);
  EXPECT_NEAR(predicted["target_error"].get<double>(), err / 4, 1e-6);

  // Stopped (max_samples below the samples taken: done), JSON and CSV hold the same numbers.
  auto r = patch("/api/sessions/" + sid + "/scene", R"({"render": {"max_samples": 1}})");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  json frozen = json::object();
  for (auto end = Clock::now() + 5s; Clock::now() < end && !frozen.value("done", false);) {
    std::this_thread::sleep_for(50ms);
    frozen = getJson(base);
  }
  ASSERT_TRUE(frozen.value("done", false)) << frozen.dump();
  EXPECT_TRUE(frozen["max_samples_reached"].get<bool>());
  EXPECT_FALSE(frozen["converged"].get<bool>());
  EXPECT_GE(frozen["points"].size(), lastCount) << "a change of max_samples keeps the accumulation and the series";
  auto csv = get(base + "?format=csv");
  ASSERT_TRUE(csv);
  ASSERT_EQ(csv->status, 200);
  EXPECT_EQ(csv->get_header_value("Content-Type").rfind("text/csv", 0), 0u) << csv->get_header_value("Content-Type");
  std::istringstream lines(csv->body);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "elapsed_ms,spp,rel_error,passes");
  json again = getJson(base);
  size_t row = 0;
  while (std::getline(lines, line)) {
    ASSERT_LT(row, again["points"].size()) << line;
    const json& p = again["points"][row++];
    double elapsed = 0, relError = 0;
    unsigned long long spp = 0, passes = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%llu,%lf,%llu", &elapsed, &spp, &relError, &passes), 4) << line;
    EXPECT_EQ(elapsed, p["elapsed_ms"].get<double>());
    EXPECT_EQ(spp, p["spp"].get<uint64_t>());
    EXPECT_EQ(relError, p["rel_error"].get<double>());
    EXPECT_EQ(passes, p["passes"].get<uint64_t>());
  }
  EXPECT_EQ(row, again["points"].size());
  // max_points thins evenly in log-time, keeping the first and the last point.
  json thin = getJson(base + "?max_points=3");
  ASSERT_LE(thin["points"].size(), 3u);
  ASSERT_GE(thin["points"].size(), 2u);
  EXPECT_EQ(thin["points"].front(), again["points"].front());
  EXPECT_EQ(thin["points"].back(), again["points"].back());
  EXPECT_EQ(thin["fit"], again["fit"]) << "the fit uses the whole series";

  // A change that restarts accumulation starts a new series.
  r = patch("/api/sessions/" + sid + "/scene", R"({"render": {"sampling": "uniform", "max_samples": 1048576}})");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  json restarted = getJson(base);
  EXPECT_LT(restarted["points"].size(), again["points"].size()) << restarted.dump();
  EXPECT_EQ(restarted["sampling"], "uniform");
  EXPECT_EQ(del("/api/sessions/" + sid)->status, 204);
}

TEST_F(Convergence, BadQueriesAre400) {
  const std::string base = "/api/sessions/default/convergence";
  expectError(get(base + "?format=xml"), 400, "format");
  for (const char* t : {"0", "1", "-0.5", "abc", "0.1x", "nan", "inf", ""})
    expectError(get(base + "?target=" + t), 400, "target");
  for (const char* n : {"1", "0", "2001", "x", "-3"}) expectError(get(base + "?max_points=" + n), 400, "max_points");
  expectError(get("/api/sessions/nosuchsession/convergence"), 404, "session");
}

TEST_F(Convergence, TargetErrorStopsRendering) {
  constexpr double kTarget = 0.2;
  std::string sid = createSession(skyLambert("cosine", 64, kMaxSamplesForever, kTarget, 1));
  ASSERT_FALSE(sid.empty());
  const std::string session = "/api/sessions/" + sid;
  // Waits for samples it will never get: the wait ends when rendering is done.
  auto r = get(session + "/frame?format=pfm&min_spp=1000000");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  json stats = getJson(session + "/stats");
  EXPECT_TRUE(stats["converged"].get<bool>()) << stats.dump();
  EXPECT_FALSE(stats["max_samples_reached"].get<bool>()) << stats.dump();
  EXPECT_TRUE(stats["done"].get<bool>()) << stats.dump();
  EXPECT_EQ(stats["target_error"], kTarget);
  ASSERT_TRUE(stats["rel_error"].is_number()) << stats.dump();
  EXPECT_LE(stats["rel_error"].get<double>(), kTarget);
  EXPECT_GE(stats["spp"].get<uint64_t>(), 16u) << "judged from kMinSppForTarget samples on";
  EXPECT_EQ(std::stoull(r->get_header_value("X-Samples")), stats["spp"].get<uint64_t>()) << "the final frame";
  // Stopped: no more samples while watched.
  std::this_thread::sleep_for(400ms);
  json later = getJson(session + "/stats");
  EXPECT_EQ(later["spp"], stats["spp"]);
  json c = getJson(session + "/convergence");
  EXPECT_EQ(c["target_error"], kTarget);
  ASSERT_FALSE(c["points"].empty());
  EXPECT_LE(c["points"].back()["rel_error"].get<double>(), kTarget);
  EXPECT_TRUE(c["converged"].get<bool>());

  // max_samples first: done, but not converged (a new sampling mode restarts the accumulation).
  r = put(session + "/scene", skyLambert("uniform", 64, 32, 0.0001).dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  r = get(session + "/frame?format=pfm&min_spp=1000000");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  stats = getJson(session + "/stats");
  EXPECT_EQ(stats["spp"], 32) << stats.dump();
  EXPECT_TRUE(stats["max_samples_reached"].get<bool>()) << stats.dump();
  EXPECT_FALSE(stats["converged"].get<bool>()) << stats.dump();
  EXPECT_TRUE(stats["done"].get<bool>());
  EXPECT_EQ(del(session)->status, 204);
}

TEST_F(Convergence, StrategyJobComparesModesAtEqualTime) {
  json request{{"scene", skyLambert("mis", 64, 64)}, {"time_ms", 300}, {"reference_ms", 1200}};
  auto r = post("/api/jobs/convergence", request.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  json started = bodyJson(r);
  ASSERT_TRUE(started["id"].is_string());
  EXPECT_EQ(started["kind"], "convergence");
  EXPECT_EQ(started["modes"], json({"cosine", "brdf", "environment", "mis"})) << "the default modes";
  EXPECT_EQ(started["time_ms"], 300);
  json job = waitForJob(started["id"], 90s);
  ASSERT_EQ(job.value("state", ""), "done") << job.dump();
  EXPECT_EQ(job["progress"], 1.0);
  EXPECT_EQ(job["request"]["time_ms"], 300);
  const json& result = job["result"];
  ASSERT_TRUE(result["modes"].is_array()) << job.dump();
  ASSERT_EQ(result["modes"].size(), 4u);
  EXPECT_GT(result["reference"]["spp"].get<uint64_t>(), 0u);
  EXPECT_GT(result["reference"]["mean_luminance"].get<double>(), 0.0);
  EXPECT_GT(result["reference"]["pixels"].get<uint64_t>(), 100u);
  EXPECT_EQ(result["checkpoints_ms"].size(), 16u);
  std::set<std::string> names;
  for (const json& m : result["modes"]) {
    const std::string name = m["sampling"];
    names.insert(name);
    EXPECT_TRUE(m["estimator"].is_string());
    EXPECT_TRUE(m["warnings"].is_array());
    const json& curve = m["curve"];
    ASSERT_GE(curve.size(), 4u) << name << ": " << m.dump();
    for (size_t i = 1; i < curve.size(); ++i) {
      EXPECT_GT(curve[i]["elapsed_ms"].get<double>(), curve[i - 1]["elapsed_ms"].get<double>()) << name;
      EXPECT_GT(curve[i]["spp"].get<uint64_t>(), curve[i - 1]["spp"].get<uint64_t>()) << name;
    }
    for (const json& p : curve) {
      ASSERT_TRUE(p["raw_rel_error"].is_number()) << name << ": " << p.dump();
      ASSERT_TRUE(p["true_rel_error"].is_number()) << name << ": " << p.dump();
      EXPECT_GE(p["true_rel_error"].get<double>(), 0.0);
      EXPECT_LE(p["true_rel_error"].get<double>(), p["raw_rel_error"].get<double>() + 1e-12);
    }
    // The error against the reference falls as the samples grow.
    EXPECT_LT(curve.back()["raw_rel_error"].get<double>(), curve.front()["raw_rel_error"].get<double>()) << name;
    // Equal time: every mode rendered for its budget, none far beyond (one pass at most).
    const json& final = m["final"];
    EXPECT_GE(final["elapsed_ms"].get<double>(), 300.0) << name;
    EXPECT_LT(final["elapsed_ms"].get<double>(), 600.0) << name;
    EXPECT_TRUE(final["relmse"].is_number()) << name;
    EXPECT_NEAR(final["relmse"].get<double>(), std::pow(final["true_rel_error"].get<double>(), 2), 1e-12);
    // relMSE(cosine) / relMSE(mode): a positive number, or null when a relMSE is 0.
    const json& ratio = m["equal_time_relmse_vs_cosine"];
    EXPECT_TRUE(ratio.is_null() || ratio.get<double>() > 0) << name << ": " << ratio;
    EXPECT_EQ(result["equal_time_relmse_vs_cosine"][name], ratio);
    if (name == "cosine" && ratio.is_number()) {
      EXPECT_DOUBLE_EQ(ratio.get<double>(), 1.0);
    }
  }
  EXPECT_EQ(names, (std::set<std::string>{"cosine", "brdf", "environment", "mis"}));
  EXPECT_TRUE(result["best"].is_null() || names.count(result["best"].get<std::string>())) << result["best"];
}

TEST_F(Convergence, StrategyJobWithoutCosineHasNoRatios) {
  json request{{"scene", skyLambert("mis", 32, 64)}, {"modes", {"uniform"}}, {"time_ms", 100}, {"reference_ms", 100}};
  auto r = post("/api/jobs/convergence", request.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  json job = waitForJob(bodyJson(r)["id"], 60s);
  ASSERT_EQ(job.value("state", ""), "done") << job.dump();
  ASSERT_EQ(job["result"]["modes"].size(), 1u);
  EXPECT_EQ(job["result"]["modes"][0]["sampling"], "uniform");
  EXPECT_TRUE(job["result"]["equal_time_relmse_vs_cosine"].is_null());
}

TEST_F(Convergence, StrategyJobCanBeCancelled) {
  json request{{"scene", skyLambert("mis", 64, 64)}, {"time_ms", 60000}, {"reference_ms", 240000}};
  auto r = post("/api/jobs/convergence", request.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string id = bodyJson(r)["id"];
  std::this_thread::sleep_for(300ms);
  r = del("/api/jobs/" + id);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(bodyJson(r)["state"], "cancelled");
  json job = waitForJob(id, 10s);
  EXPECT_EQ(job["state"], "cancelled");
  EXPECT_FALSE(job.contains("result"));
  expectError(del("/api/jobs/job-999999"), 404, "id");
  // The worker is free again: a short job runs to the end.
  request = {{"scene", skyLambert("cosine", 32, 64)}, {"modes", {"cosine"}}, {"time_ms", 100}, {"reference_ms", 100}};
  r = post("/api/jobs/convergence", request.dump());
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  EXPECT_EQ(waitForJob(bodyJson(r)["id"], 60s)["state"], "done");
}

TEST_F(Convergence, BadJobRequestsAre400) {
  const json scene = skyLambert("mis", 32, 64);
  auto job = [&](const json& body) { return post("/api/jobs/convergence", body.dump()); };
  expectError(job(json::array()), 400, "");
  expectError(job({{"scene", scene}, {"budget", 3}}), 400, "budget");
  expectError(job({{"time_ms", 300}}), 400, "scene");
  expectError(job({{"scene", "sky"}}), 400, "scene");
  expectError(job({{"scene", {{"render", {{"width", 5}}}}}}), 400, "scene.render.width");
  expectError(job({{"scene", {{"environment", {{"name", "nowhere"}}}}}}), 404, "scene.environment.name");
  expectError(job({{"scene", scene}, {"modes", "cosine"}}), 400, "modes");
  expectError(job({{"scene", scene}, {"modes", json::array()}}), 400, "modes");
  expectError(job({{"scene", scene}, {"modes", {"cosine", "importance"}}}), 400, "modes[1]");
  expectError(job({{"scene", scene}, {"modes", {"cosine", "cosine"}}}), 400, "modes[1]");
  expectError(job({{"scene", scene}, {"modes", {3}}}), 400, "modes[0]");
  for (const json& t : {json(50), json(60001), json(300.5), json("300"), json(nullptr), json(-1)})
    expectError(job({{"scene", scene}, {"time_ms", t}}), 400, "time_ms");
  expectError(job({{"scene", scene}, {"reference_ms", 240001}}), 400, "reference_ms");
  expectError(job({{"scene", {{"render", {{"width", 2048}, {"height", 1024}}}}}}), 400, "scene.render");
  auto bad = post("/api/jobs/convergence", "{not json");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
}

}  // namespace
}  // namespace brdfa::itest
