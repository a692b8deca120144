// Measured BRDFs over HTTP: MERL files made by the tests (tests/support/merl_files.h) uploaded
// as assets of kind `measured`, then named as BRDFs in scenes, analyses and checks; bad files
// refused with 400 and nothing stored; a budget that cannot hold a table answers 507.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include <stdlib.h>

#include "brdfa/measured.h"
#include "merl_files.h"
#include "server_fixture.h"

namespace brdfa::itest {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

httplib::MultipartFormDataItems merlForm(const std::string& bytes, const std::string& fileName = "table.binary",
                                         const std::string& kind = "") {
  httplib::MultipartFormDataItems items = {{"file", bytes, fileName, "application/octet-stream"}};
  if (!kind.empty()) items.push_back({"kind", kind, "", ""});
  return items;
}

const std::string& ggxFile() {
  static const std::string bytes = testsupport::ggxMerl(0.3, {0.95, 0.64, 0.54});
  return bytes;
}
const std::string& whiteFile() {
  static const std::string bytes = testsupport::lambertMerl({1, 1, 1});
  return bytes;
}

class Measured : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/brdfa-measured-XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl), nullptr);
    root_ = tmpl;
  }
  void TearDown() override {
    if (server_.running()) {
      if (HasFailure()) std::fprintf(stderr, "---- server log ----\n%s\n", server_.logTail(4000).c_str());
      EXPECT_EQ(server_.terminate(), 0);
    }
    std::error_code ec;
    fs::remove_all(root_, ec);
  }
  void start(std::vector<std::string> extra = {}) {
    if (server_.running()) {
      EXPECT_EQ(server_.terminate(), 0);
    }
    extra.insert(extra.begin(), {"--data-dir", root_ + "/data"});
    ASSERT_EQ(server_.start(extra), "");
  }
  httplib::Result upload(const httplib::MultipartFormDataItems& items) {
    return server_.client(60)->Post("/api/assets", items);
  }
  json getJson(const std::string& path) {
    auto r = server_.client()->Get(path);
    EXPECT_TRUE(r && r->status == 200) << path << ": " << (r ? r->body : "no answer");
    return r ? bodyJson(r) : json();
  }
  json postJson(const std::string& path, const json& body, int status = 200) {
    auto r = server_.client(60)->Post(path, body.dump(), "application/json");
    EXPECT_TRUE(r && r->status == status) << path << ": " << (r ? r->body : "no answer");
    return r ? bodyJson(r) : json();
  }
  uint64_t rendererAssetBytes() {
    return getJson("/api/health")["memory"]["renderer"].value("assets_bytes", uint64_t(0));
  }
  std::vector<std::string> storedFiles() {
    std::vector<std::string> names;
    std::error_code ec;
    for (fs::directory_iterator it(root_ + "/data/assets", ec), end; !ec && it != end; it.increment(ec))
      names.push_back(it->path().filename().string());
    return names;
  }
  // Uploads `bytes` and returns the asset (a failed expectation when it is not 201).
  json uploadTable(const std::string& bytes, const std::string& fileName) {
    auto r = upload(merlForm(bytes, fileName));
    EXPECT_TRUE(r && r->status == 201) << (r ? r->body : "no answer");
    return r ? bodyJson(r) : json();
  }

  // Runs the first sh block after `heading` of docs/api.md against this server, from a folder
  // holding examples/make_merl.py; what it printed (a failed assertion when it fails).
  std::string runDocsExample(const std::string& heading) {
    const std::string api = readRepoFile("docs/api.md");
    const size_t section = api.find("\n" + heading + "\n");
    EXPECT_NE(section, std::string::npos) << heading;
    if (section == std::string::npos) return {};
    const size_t begin = api.find("```sh\n", section), end = api.find("```\n", begin + 6);
    EXPECT_NE(end, std::string::npos);
    if (end == std::string::npos) return {};
    std::string script = api.substr(begin + 6, end - begin - 6);
    for (size_t at; (at = script.find("127.0.0.1:8080")) != std::string::npos;)
      script.replace(at, 14, "127.0.0.1:" + std::to_string(server_.port()));
    std::error_code ec;
    fs::create_directories(root_ + "/examples");
    fs::copy_file(std::string(BRDFA_SOURCE_DIR) + "/examples/make_merl.py", root_ + "/examples/make_merl.py",
                  fs::copy_options::overwrite_existing, ec);
    std::ofstream(root_ + "/example.sh") << "set -e\ncd " << root_ << "\n" << script;
    FILE* out = ::popen(("bash " + root_ + "/example.sh").c_str(), "r");
    EXPECT_NE(out, nullptr);
    if (!out) return {};
    std::string printed;
    char buf[4096];
    for (size_t n; (n = std::fread(buf, 1, sizeof buf, out)) > 0;) printed.append(buf, n);
    EXPECT_EQ(::pclose(out), 0) << printed;
    return printed;
  }

  std::string root_;
  ServerProcess server_;
};

TEST_F(Measured, AnUploadedTableIsABrdfInScenesPlotsAndChecks) {
  start();
  const uint64_t assetsBefore = rendererAssetBytes();
  const json ggx = uploadTable(ggxFile(), "ggx.binary");
  const json white = uploadTable(whiteFile(), "white.binary");
  const std::string id = ggx.value("id", ""), whiteId = white.value("id", "");
  ASSERT_EQ(id.rfind("merl_", 0), 0u) << ggx.dump();
  EXPECT_EQ(ggx["kind"], "measured");
  EXPECT_EQ(ggx["format"], "merl");
  EXPECT_EQ(ggx["bytes"], kMerlFileBytes);
  EXPECT_GT(ggx.value("bins", 0), 0);
  EXPECT_LT(ggx.value("bins", uint64_t(0)), kMerlBins);  // bins below the horizon hold no data
  EXPECT_EQ(white["bins"], kMerlBins);
  // Both tables are held from their upload on, counted in the renderer's memory.
  EXPECT_GE(rendererAssetBytes(), assetsBefore + 2 * 3 * kMerlBins * sizeof(float));
  EXPECT_EQ(getJson("/api/assets?kind=measured").size(), 2u);

  // A scene: the white table renders 1 in the furnace, as a white Lambertian does.
  json scene = {{"environment", {{"name", "furnace"}, {"visible", false}}},
                {"objects", {{{"mesh", "sphere"}, {"brdf", whiteId}}}},
                {"render", {{"width", 24}, {"height", 24}, {"max_samples", 4}, {"sampling", "cosine"}}}};
  auto put = server_.client()->Put("/api/sessions/default/scene", scene.dump(), "application/json");
  ASSERT_TRUE(put && put->status == 200) << (put ? put->body : "no answer");
  auto frame = server_.client(60)->Get("/api/sessions/default/frame?format=pfm&min_spp=4");
  ASSERT_TRUE(frame && frame->status == 200);
  Image img;
  ASSERT_TRUE(decodeImage(frame->body, img));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(img.at(12, 12, c), 1.0f, 1e-4f);

  // A polar plot overlays the table with the analytic GGX it was made from.
  const json polar =
      postJson("/api/analysis/polar", {{"series", {{{"brdf", id}}, {{"brdf", "ggx"}}}}, {"theta_i", 30}});
  ASSERT_EQ(polar["series"].size(), 2u);
  const json& m = polar["series"][0]["values"]["incidence"];
  const json& a = polar["series"][1]["values"]["incidence"];
  ASSERT_EQ(m.size(), a.size());
  double err = 0, ref = 0;
  for (size_t i = 0; i < m.size(); ++i) {
    if (m[i].is_null() || a[i].is_null()) continue;
    const double x = a[i][1].get<double>(), y = m[i][1].get<double>();
    err += (y - x) * (y - x);
    ref += x * x;
  }
  EXPECT_LT(std::sqrt(err / ref), 0.02);

  // Its directional albedo is the analytic GGX's within the two estimates' errors and the
  // table's interpolation; the lobe and the slice are drawn from it too.
  const json albedo =
      postJson("/api/analysis/albedo", {{"series", {{{"brdf", id}}, {{"brdf", "ggx"}}}}, {"theta_v", {0, 45, 80}}});
  ASSERT_EQ(albedo["series"].size(), 2u);
  for (size_t v = 0; v < 3; ++v) {
    const double em = albedo["series"][0]["values"][v][1], ea = albedo["series"][1]["values"][v][1];
    const double se = std::hypot(albedo["series"][0]["std_error"][v][1].get<double>(),
                                 albedo["series"][1]["std_error"][v][1].get<double>());
    EXPECT_NEAR(em, ea, 3 * se + 0.01 * ea) << "view " << v << ": " << albedo.dump().substr(0, 400);
  }
  for (const char* kind : {"lobe", "slice"}) {
    const json plot = postJson(std::string("/api/analysis/") + kind, {{"series", {{{"brdf", id}}}}});
    EXPECT_EQ(plot.value("kind", ""), kind);
  }

  // Side by side: a session with analytic GGX against one with the table, same seed: the
  // difference is the table's interpolation, a fraction of a percent.
  json sideScene = {{"environment", {{"name", "sky"}, {"visible", false}}},
                    {"objects", {{{"mesh", "sphere"}, {"brdf", "ggx"}}}},
                    {"render", {{"width", 48}, {"height", 48}, {"max_samples", 64}, {"sampling", "environment"}}}};
  auto analyticSession = server_.client()->Post("/api/sessions", sideScene.dump(), "application/json");
  sideScene["objects"][0]["brdf"] = id;
  auto measuredSession = server_.client()->Post("/api/sessions", sideScene.dump(), "application/json");
  ASSERT_TRUE(analyticSession && measuredSession && analyticSession->status == 201 && measuredSession->status == 201);
  const std::string sa = bodyJson(analyticSession).value("id", ""), sb = bodyJson(measuredSession).value("id", "");
  for (const std::string& s : {sa, sb})
    ASSERT_TRUE(server_.client(60)->Get("/api/sessions/" + s + "/frame?min_spp=64"));
  const json diff = getJson("/api/sessions/" + sa + "/difference?against=" + sb + "&format=json");
  EXPECT_LT(diff.value("rel_rms", 1.0), 0.01) << diff.dump();

  // The checks: its albedo (below 1: GGX loses energy) and its reciprocity, as measured.
  const json job = postJson("/api/jobs/validate", {{"names", {id}}}, 202);
  json done;
  for (int i = 0; i < 600; ++i) {
    done = getJson("/api/jobs/" + job.value("id", ""));
    if (done.value("state", "") != "running" && done.value("state", "") != "queued") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_EQ(done.value("state", ""), "done") << done.dump();
  const json& checks = done["results"][0]["checks"];
  EXPECT_TRUE(done["results"][0].value("ok", false)) << done.dump();
  EXPECT_LT(checks.value("max_albedo", 2.0), 1.0) << checks.dump();
  EXPECT_LT(checks.value("max_reciprocity_error", 1.0), 1e-3) << checks.dump();

  // A saved BRDF may not take a measured upload's name.
  auto shadow = server_.client()->Put("/api/brdfs/" + id, readRepoFile("shaders/brdfs/ggx.brdf"), "text/plain");
  ASSERT_TRUE(shadow);
  EXPECT_EQ(shadow->status, 400) << shadow->body;

  // After a restart the table is registered again and renders the same.
  start();
  put = server_.client()->Put("/api/sessions/default/scene", scene.dump(), "application/json");
  ASSERT_TRUE(put && put->status == 200) << (put ? put->body : "no answer");
  EXPECT_GE(rendererAssetBytes(), assetsBefore + 2 * 3 * kMerlBins * sizeof(float));
}

TEST_F(Measured, BadTablesAre400AndNothingIsStored) {
  start();
  std::string wrongHeader = whiteFile();
  const int32_t fullPhi[3] = {90, 90, 360};
  std::memcpy(wrongHeader.data(), fullPhi, sizeof fullPhi);
  std::vector<double> planar = testsupport::indexPlanar();
  planar[2 * kMerlBins + 1234] = std::nan("");
  const std::string withNan = writeMerl(planar);
  const std::string noData = writeMerl(std::vector<double>(3 * kMerlBins, -1.0));
  struct Case {
    std::string label, bytes, fileName, kind, reason, words;
  };
  const std::vector<Case> cases = {
      {"truncated", whiteFile().substr(0, kMerlFileBytes / 2), "t.binary", "", "invalid", "(truncated)"},
      {"one byte short", whiteFile().substr(0, kMerlFileBytes - 1), "t.binary", "", "invalid", "(truncated)"},
      {"trailing bytes", whiteFile() + "xx", "t.binary", "", "invalid", "bytes after the table"},
      {"header of another layout", wrongHeader, "t.binary", "measured", "unknown_format", "MERL"},
      {"NaN", withNan, "t.binary", "", "invalid", "NaN in the blue channel of bin (theta_h 0, theta_d 6, phi_d 154)"},
      {"no bin with data", noData, "t.binary", "", "invalid", "no bin with data"},
      {"a table called a texture", whiteFile(), "t.binary", "texture", "mislabelled", "MERL"},
      {"a table named .png", whiteFile(), "t.png", "", "mislabelled", ""},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.label);
    auto r = upload(merlForm(c.bytes, c.fileName, c.kind));
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << r->body;
    const json body = bodyJson(r);
    EXPECT_EQ(body.value("reason", ""), c.reason) << r->body;
    EXPECT_NE(body.value("message", "").find(c.words), std::string::npos) << r->body;
  }
  EXPECT_TRUE(storedFiles().empty());
  EXPECT_EQ(getJson("/api/assets?kind=measured").size(), 0u);
  EXPECT_EQ(getJson("/api/health").value("status", ""), "ok");
}

// Starts the server with --max-memory `mib` and returns the renderer's room: its budget less
// what it holds.
int64_t rendererRoom(const json& health) {
  const json& r = health["memory"]["renderer"];
  int64_t used = 0;
  for (const char* k :
       {"process_bytes", "compiles_bytes", "render_targets_bytes", "assets_bytes", "transfers_bytes", "programs_bytes"})
    used += r.value(k, int64_t(0));
  return r.value("budget_bytes", int64_t(0)) - used;
}

TEST_F(Measured, ABudgetThatCannotHoldATableAnswers507) {
  // Below 1 GiB the compile workers' share is at its floor, so there a change of budget changes
  // only the renderer's room (7/8 of it). Find a budget with 200 MiB of room (what the processes
  // hold at start differs between builds: the sanitizers' is larger), then give the renderer
  // 40 MiB, less than the 88 MB a table needs while it loads.
  const int64_t mib = 1 << 20;
  int64_t roomy = 768 * mib;
  start({"--max-memory", std::to_string(roomy / mib)});
  int64_t room = rendererRoom(getJson("/api/health"));
  if (room < 200 * mib) {
    roomy += (200 * mib - room) * 8 / 7;
    ASSERT_LT(roomy, 1024 * mib) << "the processes hold too much at start for this check";
    start({"--max-memory", std::to_string(roomy / mib)});
    room = rendererRoom(getJson("/api/health"));
  }
  ASSERT_GT(room, 150 * mib) << "the check needs a budget with room for a table";
  const int64_t smaller = roomy - (room - 40 * mib) * 8 / 7;
  start({"--max-memory", std::to_string(smaller / mib)});
  auto r = upload(merlForm(whiteFile()));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 507) << r->body;
  const json body = bodyJson(r);
  EXPECT_EQ(body.value("error", ""), "memory_budget") << r->body;
  EXPECT_EQ(body.value("reason", ""), "memory_budget") << r->body;
  EXPECT_TRUE(storedFiles().empty());
  EXPECT_EQ(getJson("/api/health").value("status", ""), "ok");
  // The same upload where there is room.
  start({"--max-memory", std::to_string(roomy / mib)});
  EXPECT_EQ(uploadTable(whiteFile(), "white.binary").value("kind", ""), "measured");
}

// docs/api.md's example of measured BRDFs, run as written (the port aside) in a folder with
// the examples: the table it makes uploads, the session takes it, the polar plot overlays it.
TEST_F(Measured, TheDocsExampleRunsAsWritten) {
  if (std::system("command -v python3 >/dev/null") != 0) GTEST_SKIP() << "python3 is not installed";
  start();
  const std::string printed = runDocsExample("### Measured BRDFs");
  // The PATCH's scene names the table; the polar plot has its series and GGX's.
  EXPECT_NE(printed.find("\"brdf\":\"merl_"), std::string::npos) << printed.substr(0, 2000);
  EXPECT_NE(printed.find("\"kind\":\"polar\""), std::string::npos) << printed.substr(0, 2000);
  const json assets = getJson("/api/assets?kind=measured");
  ASSERT_EQ(assets.size(), 1u);
  EXPECT_EQ(assets[0].value("bins", 0), 1096216) << "the count docs/api.md quotes";
}

TEST_F(Measured, TheFitExampleRunsAsWritten) {
  if (std::system("command -v python3 >/dev/null") != 0) GTEST_SKIP() << "python3 is not installed";
  start();
  const std::string printed = runDocsExample("## Fit jobs");
  // The last line: the fitted parameters (python's dict) and the final loss.
  const size_t roughness = printed.find("'roughness': ");
  ASSERT_NE(roughness, std::string::npos) << printed.substr(0, 2000);
  EXPECT_NEAR(std::stod(printed.substr(roughness + 13)), 0.2, 0.002) << printed;
  const size_t f0 = printed.find("'F0': [");
  ASSERT_NE(f0, std::string::npos) << printed;
  EXPECT_NEAR(std::stod(printed.substr(f0 + 7)), 0.8, 0.008) << printed;
  EXPECT_LT(std::stod(printed.substr(printed.rfind(' ') + 1)), 1e-8) << printed;
}

}  // namespace
}  // namespace brdfa::itest
