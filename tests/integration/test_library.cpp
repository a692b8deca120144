// Saved user BRDFs (<data dir>/brdfs), presets, and batch test jobs, each against a real server
// with a data folder of the test's own (so a restart can find what the last run saved).
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "server_fixture.h"

namespace brdfa::itest {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

// A fresh folder, removed at the end of the test.
struct TempDir {
  std::string path;
  TempDir() {
    char tmpl[] = "/tmp/brdfa-libtest-XXXXXX";
    if (::mkdtemp(tmpl)) path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    if (!path.empty()) fs::remove_all(path, ec);
  }
};

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeFile(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

// A valid Lambertian BRDF that differs per `k` in its code (a new shader each time) and in
// length (kilobytes of comment), so a torn write could not pass for another version.
std::string lambertVersion(int k) {
  std::string pad(2000 + (k % 7) * 3000, 'a' + static_cast<char>(k % 26));
  return "analytic\n# version " + std::to_string(k) + " " + pad +
         "\n::begin parameters\ncolor Kd 1 1 1\n::end parameters\n::begin shader\n"
         "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)\n{\n    return Kd * " +
         std::to_string(1.0 - k * 1e-6) + " / 3.14159265358979;\n}\n::end shader\n# end " + std::to_string(k) + "\n";
}

// A server on `dataDir`; fails the test when it does not start.
std::unique_ptr<ServerProcess> startOn(const std::string& dataDir, std::string* error = nullptr,
                                       const std::vector<std::string>& extraArgs = {}) {
  auto s = std::make_unique<ServerProcess>();
  std::vector<std::string> args = {"--data-dir", dataDir, "--idle-timeout", "3"};
  args.insert(args.end(), extraArgs.begin(), extraArgs.end());
  std::string err = s->start(args);
  if (error) *error = err;
  if (!err.empty()) ADD_FAILURE() << "server did not start: " << err;
  return s;
}

json listNames(ServerProcess& s, json* list = nullptr) {
  auto r = s.client()->Get("/api/brdfs");
  json names = json::array();
  if (!r || r->status != 200) return names;
  json l = bodyJson(r);
  for (const json& b : l) names.push_back(b["name"]);
  if (list) *list = l;
  return names;
}

bool contains(const json& arr, const std::string& s) {
  for (const json& v : arr)
    if (v == s) return true;
  return false;
}

TEST(Library, SavedBrdfSurvivesRestartAndRenders) {
  TempDir dir;
  auto s = startOn(dir.path);
  ASSERT_TRUE(s->running());
  auto r = s->client()->Put("/api/brdfs/saved_one", kLambertWhite, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  EXPECT_EQ(readFile(fs::path(dir.path) / "brdfs" / "saved_one.brdf"), kLambertWhite);
  EXPECT_EQ(s->terminate(), 0);

  s = startOn(dir.path);
  ASSERT_TRUE(s->running());
  json list;
  json names = listNames(*s, &list);
  ASSERT_TRUE(contains(names, "saved_one")) << list.dump();
  for (const json& b : list)
    if (b["name"] == "saved_one") {
      EXPECT_EQ(b["builtin"], false);
      EXPECT_FALSE(b.contains("broken"));
    }
  json one = bodyJson(s->client()->Get("/api/brdfs/saved_one"));
  EXPECT_EQ(one["source"], kLambertWhite);

  json body = furnaceScene("saved_one", json::object(), 24, 16);
  body["spp"] = 16;
  body["format"] = "pfm";
  r = s->client()->Post("/api/render", body.dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  Image img;
  ASSERT_TRUE(decodeImage(r->body, img));
  auto pixels = interiorPixels(img);
  ASSERT_FALSE(pixels.empty());
  for (auto [x, y] : pixels) ASSERT_NEAR(img.lum(x, y), 1.0f, 1e-3f) << x << "," << y;

  // Deleting removes the file too: gone after another restart.
  r = s->client()->Delete("/api/brdfs/saved_one");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 204);
  EXPECT_FALSE(fs::exists(fs::path(dir.path) / "brdfs" / "saved_one.brdf"));
  EXPECT_FALSE(contains(listNames(*s), "saved_one"));
  EXPECT_EQ(s->terminate(), 0);
  s = startOn(dir.path);
  EXPECT_FALSE(contains(listNames(*s), "saved_one"));
  EXPECT_EQ(s->terminate(), 0);
}

// --hot-load builds, after start-up, the pipelines of BRDFs compiled in an earlier run (from
// the SPIR-V disk cache, compiling nothing); without it start-up prepares nothing.
TEST(Library, HotLoadBuildsCachedPipelinesWithoutCompiling) {
  TempDir dir;
  json body = furnaceScene("hot_one", json::object(), 24, 4);
  body["spp"] = 4;
  auto s = startOn(dir.path);
  ASSERT_TRUE(s->running());
  auto r = s->client()->Put("/api/brdfs/hot_one", kLambertWhite, "text/plain");
  ASSERT_TRUE(r && r->status == 201) << (r ? r->body : "no answer");
  r = s->client()->Post("/api/render", body.dump(), "application/json");  // the furnace variant
  ASSERT_TRUE(r && r->status == 200);
  EXPECT_EQ(s->terminate(), 0);

  // Without the flag: nothing built at start.
  s = startOn(dir.path);
  json health = bodyJson(s->client()->Get("/api/health"));
  EXPECT_EQ(health["hot_load"]["enabled"], false) << health.dump();
  EXPECT_EQ(health["compiler"]["pipelines_created"], 0) << health.dump();
  EXPECT_EQ(s->terminate(), 0);

  s = startOn(dir.path, nullptr, {"--hot-load"});
  ASSERT_TRUE(s->running());
  for (auto deadline = Clock::now() + std::chrono::seconds(120); Clock::now() < deadline;) {
    health = bodyJson(s->client()->Get("/api/health"));
    if (health["hot_load"]["done"] == true) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_EQ(health["hot_load"]["done"], true) << health.dump();
  EXPECT_EQ(health["hot_load"]["enabled"], true);
  // hot_one was compiled in two variants (PUT validation: cubemap; the render: furnace).
  EXPECT_GE(health["hot_load"]["pipelines"], 2) << health.dump();
  EXPECT_EQ(health["hot_load"]["visited"], health["hot_load"]["brdfs"]);
  EXPECT_EQ(health["compiler"]["glsl_compiles"], 0) << "hot-load must never compile: " << health.dump();
  const json created = health["compiler"]["pipelines_created"];
  EXPECT_EQ(created, health["hot_load"]["pipelines"]);

  // Its first use is served by the preloaded pipeline.
  r = s->client()->Post("/api/render", body.dump(), "application/json");
  ASSERT_TRUE(r && r->status == 200);
  health = bodyJson(s->client()->Get("/api/health"));
  EXPECT_EQ(health["compiler"]["pipelines_created"], created) << health.dump();
  EXPECT_EQ(health["compiler"]["glsl_compiles"], 0) << health.dump();
  EXPECT_EQ(s->terminate(), 0);
}

TEST(Library, BrokenSavedFileIsListedWithItsErrorAndStartupGoesOn) {
  TempDir dir;
  writeFile(fs::path(dir.path) / "brdfs" / "good.brdf", kLambertWhite);
  writeFile(fs::path(dir.path) / "brdfs" / "bad.brdf", "analytic\n::begin parameters\nfloat a 0 1\n");
  writeFile(fs::path(dir.path) / "brdfs" / ".tmp-good.brdf.Ab12Cd", "analytic\n::begin para");
  // A crash long ago left it; a young one may be another replica's save in progress, and stays.
  fs::last_write_time(fs::path(dir.path) / "brdfs" / ".tmp-good.brdf.Ab12Cd",
                      fs::file_time_type::clock::now() - std::chrono::hours(1));
  writeFile(fs::path(dir.path) / "brdfs" / ".tmp-other.brdf.Zz99Yy", "analytic\n::begin para");
  auto s = startOn(dir.path);
  ASSERT_TRUE(s->running());
  json list;
  json names = listNames(*s, &list);
  EXPECT_TRUE(contains(names, "good"));
  ASSERT_TRUE(contains(names, "bad")) << list.dump();
  for (const json& b : list) {
    EXPECT_EQ(b["name"].get<std::string>().find("tmp"), std::string::npos) << b.dump();
    if (b["name"] == "bad") {
      EXPECT_EQ(b["broken"], true);
      EXPECT_TRUE(b["error"]["message"].is_string()) << b.dump();
    }
  }
  EXPECT_FALSE(fs::exists(fs::path(dir.path) / "brdfs" / ".tmp-good.brdf.Ab12Cd")) << "stale temp file kept";
  EXPECT_TRUE(fs::exists(fs::path(dir.path) / "brdfs" / ".tmp-other.brdf.Zz99Yy")) << "young temp file removed";
  // A scene cannot use it; a PUT fixes it.
  json body = furnaceScene("bad", json::object(), 16, 1);
  body["spp"] = 1;
  auto r = s->client()->Post("/api/render", body.dump(), "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404) << r->body;
  r = s->client()->Put("/api/brdfs/bad", kLambertWhite, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  json fixed = bodyJson(s->client()->Get("/api/brdfs/bad"));
  EXPECT_FALSE(fixed.contains("broken")) << fixed.dump();
  EXPECT_EQ(s->terminate(), 0);
}

TEST(Library, SigkillDuringSavesLeavesOnlyCompleteFiles) {
  TempDir dir;
  auto s = startOn(dir.path);
  ASSERT_TRUE(s->running());
  const std::vector<std::string> names = {"crash_a", "crash_b"};
  std::mutex mutex;
  std::set<std::string> sent;  // every version sent (whether or not its PUT finished)
  std::atomic<int> okPuts{0};
  std::atomic<bool> stop{false};
  std::vector<std::thread> writers;
  for (size_t w = 0; w < names.size(); ++w)
    writers.emplace_back([&, w] {
      auto cli = s->client(10);
      for (int k = static_cast<int>(w) * 100000; !stop; ++k) {
        std::string text = lambertVersion(k);
        {
          std::lock_guard lock(mutex);
          sent.insert(text);
        }
        auto r = cli->Put("/api/brdfs/" + names[w], text, "text/plain");
        if (!r) break;  // the server is gone
        if (r->status == 200 || r->status == 201) ++okPuts;
      }
    });
  std::mt19937 rng(std::random_device{}());
  auto killAt = Clock::now() + std::chrono::milliseconds(500 + rng() % 700);
  while ((Clock::now() < killAt || okPuts < 2) && Clock::now() < killAt + std::chrono::seconds(30))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_GE(okPuts.load(), 2);
  ::kill(s->pid(), SIGKILL);
  stop = true;
  for (auto& t : writers) t.join();
  std::fprintf(stderr, "SIGKILL after %d completed saves (%zu versions sent)\n", okPuts.load(), sent.size());
  s.reset();  // reaps the killed process

  size_t files = 0;
  for (const auto& e : fs::directory_iterator(fs::path(dir.path) / "brdfs")) {
    std::string name = e.path().filename().string();
    if (e.path().extension() != ".brdf") continue;
    ++files;
    std::string text = readFile(e.path());
    EXPECT_FALSE(text.empty()) << name;
    EXPECT_TRUE(sent.count(text)) << name << " is not one of the versions written (" << text.size() << " bytes)";
  }
  EXPECT_GE(files, 1u);

  s = startOn(dir.path);
  ASSERT_TRUE(s->running());
  json list;
  json got = listNames(*s, &list);
  for (const json& b : list) {
    EXPECT_FALSE(b.contains("broken")) << b.dump();
    std::string n = b["name"];
    EXPECT_TRUE(b["builtin"] == true || n == "crash_a" || n == "crash_b") << "unexpected entry " << b.dump();
  }
  // A temp file the kill left behind may stay until a start 10 minutes later (on a shared folder
  // a young one may be another replica's write in progress), but it is never listed or read.
  for (const auto& e : fs::directory_iterator(fs::path(dir.path) / "brdfs"))
    EXPECT_TRUE(e.path().extension() == ".brdf" || e.path().filename().string().rfind(".tmp-", 0) == 0)
        << "left over after restart: " << e.path();
  EXPECT_EQ(s->terminate(), 0);
}

TEST(Library, StartupTimeDoesNotGrowWithSavedBrdfs) {
  TempDir empty, full;
  for (int i = 0; i < 400; ++i)
    writeFile(fs::path(full.path) / "brdfs" / ("user_" + std::to_string(i) + ".brdf"), lambertVersion(i));
  // Best of two for each, alternating, to keep one slow start from deciding.
  auto timeStart = [](const std::string& dir, size_t* userCount) {
    auto t0 = Clock::now();
    auto s = startOn(dir);
    double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (userCount) {
      json list;
      listNames(*s, &list);
      *userCount = 0;
      for (const json& b : list) *userCount += b["builtin"] == false && !b.contains("broken");
    }
    EXPECT_EQ(s->terminate(), 0);
    return ms;
  };
  double emptyMs = 1e18, fullMs = 1e18;
  size_t users = 0;
  for (int round = 0; round < 2; ++round) {
    emptyMs = std::min(emptyMs, timeStart(empty.path, nullptr));
    fullMs = std::min(fullMs, timeStart(full.path, &users));
  }
  EXPECT_EQ(users, 400u);
  RecordProperty("startup_ms_empty", std::to_string(emptyMs));
  RecordProperty("startup_ms_400", std::to_string(fullMs));
  std::fprintf(stderr, "start-up: %.0f ms empty, %.0f ms with 400 saved BRDFs\n", emptyMs, fullMs);
  // Parsing 400 files is allowed 150 ms (compiling them would take seconds). The sanitizer
  // build's instrumented parser takes 1-3 ms a file: the bound is checked in the plain build.
  if (!kSanitizedBuild) {
    EXPECT_LE(fullMs, emptyMs * 1.2 + 150.0) << "empty " << emptyMs << " ms, 400 BRDFs " << fullMs << " ms";
  }
}

TEST(Library, SigtermDuringABatchJobExitsCleanly) {
  TempDir dir;
  auto s = startOn(dir.path);
  ASSERT_TRUE(s->running());
  for (int i = 0; i < 3; ++i) {
    auto r = s->client()->Post("/api/jobs/validate", R"({"all": true})", "application/json");
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 202) << r->body;
  }
  auto t0 = Clock::now();
  EXPECT_EQ(s->terminate(std::chrono::seconds(20)), 0) << s->logTail();
  double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  EXPECT_LT(ms, 10000.0);
}

// The rest share one server.
class LibraryApi : public ServerTest {
 protected:
  // The mean luminance of the interior pixels of BRDF `name`, with one float parameter set,
  // rendered in the hidden furnace (64x64, 256 samples); NaN, and a failure, if it did not render.
  double furnaceMean(const std::string& name, const std::string& param, double value) {
    json body = {{"scene",
                  {{"environment", {{"name", "furnace"}, {"visible", false}}},
                   {"objects", json::array({{{"brdf", name}, {"params", {{param, value}}}}})},
                   {"render", {{"width", 64}, {"height", 64}}}}},
                 {"spp", 256},
                 {"format", "pfm"}};
    auto r = post("/api/render", body.dump());
    Image img;
    if (!r || r->status != 200 || !decodeImage(r->body, img)) {
      ADD_FAILURE() << name << ": " << (r ? r->body : "no answer");
      return std::nan("");
    }
    auto interior = interiorPixels(img);
    EXPECT_GT(interior.size(), 1000u) << name;
    double sum = 0;
    for (auto [x, y] : interior) sum += img.lum(x, y);
    return sum / interior.size();
  }
};

TEST_F(LibraryApi, BuiltinsAreReadOnlyAndNamesAreChecked) {
  auto r = put("/api/brdfs/ggx", kLambertWhite, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 409) << r->body;
  r = del("/api/brdfs/ggx");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 409) << r->body;
  for (const std::string& bad :
       std::vector<std::string>{"has%20space", "dot.name", std::string(65, 'x'), "inline", "%C3%A9t%C3%A9"}) {
    r = put("/api/brdfs/" + bad, kLambertWhite, "text/plain");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << bad << ": " << r->body;
    r = del("/api/brdfs/" + bad);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << bad << ": " << r->body;
  }
  r = put("/api/brdfs/" + std::string(64, 'x'), kLambertWhite, "text/plain");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 201) << r->body;
  r = del("/api/brdfs/" + std::string(64, 'x'));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 204);

  r = put("/api/brdfs/to_delete", kLambertWhite, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201) << r->body;
  EXPECT_TRUE(contains(listNames(*server_), "to_delete"));
  r = del("/api/brdfs/to_delete");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 204);
  EXPECT_FALSE(contains(listNames(*server_), "to_delete"));
  r = del("/api/brdfs/to_delete");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404);
  r = get("/api/brdfs/to_delete");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404);
}

// curl --data-binary sends application/x-www-form-urlencoded, and curl -F a multipart form:
// a .brdf far over 8 KiB must be read as text either way.
TEST_F(LibraryApi, LargeBrdfIsReadAsTextWhateverItsContentType) {
  std::string text = readRepoFile("shaders/brdfs/lambert.brdf");
  ASSERT_FALSE(text.empty());
  while (text.size() < 64 * 1024)
    text += "# padding: a long comment, as a well-documented file has " + std::to_string(text.size()) + "\n";
  for (const char* type : {"application/x-www-form-urlencoded", "text/plain", "application/octet-stream"}) {
    auto r = post("/api/brdfs/validate", text, type);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << type << ": " << r->body.substr(0, 300);
  }
  httplib::MultipartFormDataItems form = {{"file", text, "lambert.brdf", "application/octet-stream"}};
  auto r = server_->client()->Put("/api/brdfs/big_documented", form);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 201) << r->body.substr(0, 300);
  auto stored = get("/api/brdfs/big_documented");
  ASSERT_TRUE(stored);
  EXPECT_EQ(bodyJson(stored).value("source", ""), text);
  del("/api/brdfs/big_documented");
  // Over the 1 MiB limit: 413 that says so, whatever the type.
  std::string huge(1100 * 1024, '#');
  r = post("/api/brdfs/validate", huge, "application/x-www-form-urlencoded");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 413);
  EXPECT_NE(bodyJson(r).value("message", "").find(".brdf text is larger than"), std::string::npos) << r->body;
}

TEST_F(LibraryApi, PresetsRoundTrip) {
  // On a built-in: ggx's parameters.
  json ggx = bodyJson(get("/api/brdfs/ggx"));
  json values = json::object();
  for (const json& p : ggx["params"]) {
    if (p["type"] == "float") values[p["name"].get<std::string>()] = p["max"];
    if (p["type"] == "color") values[p["name"].get<std::string>()] = json({0.25, 0.5, 0.75});
    if (p["type"] == "bool") values[p["name"].get<std::string>()] = true;
  }
  ASSERT_FALSE(values.empty()) << ggx.dump();
  EXPECT_EQ(bodyJson(get("/api/brdfs/ggx/presets")), json::array());
  auto r = put("/api/brdfs/ggx/presets/shiny", values.dump());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 201) << r->body;
  r = put("/api/brdfs/ggx/presets/shiny", values.dump());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  r = put("/api/brdfs/ggx/presets/empty", "{}");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 201) << r->body;
  EXPECT_EQ(bodyJson(get("/api/brdfs/ggx/presets")), json({"empty", "shiny"}));
  r = get("/api/brdfs/ggx/presets/shiny");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  json back = bodyJson(r);
  ASSERT_EQ(back.size(), values.size()) << back.dump();
  for (auto it = values.begin(); it != values.end(); ++it) {
    if (it->is_array())
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(back[it.key()][c].get<double>(), (*it)[c].get<double>(), 1e-6);
    else if (it->is_number())
      EXPECT_NEAR(back[it.key()].get<double>(), it->get<double>(), 1e-6);
    else
      EXPECT_EQ(back[it.key()], *it);
  }

  // Bad values: unknown name, wrong type, non-finite, not an object, bad names.
  std::string floatName, colorName;
  for (const json& p : ggx["params"]) {
    if (p["type"] == "float" && floatName.empty()) floatName = p["name"];
    if (p["type"] == "color" && colorName.empty()) colorName = p["name"];
  }
  std::vector<std::string> bad = {R"({"no_such_param": 1})", "[1, 2]", "{not json", R"({"a": 1e999})"};
  if (!floatName.empty()) {
    bad.push_back(json{{floatName, "0.5"}}.dump());
    bad.push_back(json{{floatName, nullptr}}.dump());
    bad.push_back("{\"" + floatName + "\": NaN}");
    bad.push_back("{\"" + floatName + "\": 1e300}");
  }
  if (!colorName.empty()) {
    bad.push_back(json{{colorName, {1, 2}}}.dump());
    bad.push_back(json{{colorName, 0.5}}.dump());
  }
  for (const std::string& b : bad) {
    r = put("/api/brdfs/ggx/presets/broken", b);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << b << ": " << r->body;
  }
  r = get("/api/brdfs/ggx/presets/broken");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404);
  r = put("/api/brdfs/ggx/presets/bad.name", "{}");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  r = put("/api/brdfs/no_such_brdf/presets/x", "{}");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404);

  // On a user BRDF, bools as 0/1 too; delete.
  r = put("/api/brdfs/preset_user", kLambertWhite, "text/plain");
  ASSERT_TRUE(r && (r->status == 201 || r->status == 200));
  r = put("/api/brdfs/preset_user/presets/red", R"({"Kd": [1, 0, 0]})");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 201) << r->body;
  EXPECT_EQ(bodyJson(get("/api/brdfs/preset_user/presets/red")), json({{"Kd", {1, 0, 0}}}));
  r = del("/api/brdfs/preset_user/presets/red");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 204);
  r = del("/api/brdfs/preset_user/presets/red");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404);
  EXPECT_EQ(bodyJson(get("/api/brdfs/preset_user/presets")), json::array());
  r = del("/api/brdfs/ggx/presets/shiny");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 204);
  EXPECT_EQ(bodyJson(get("/api/brdfs/ggx/presets")), json({"empty"}));
}

TEST_F(LibraryApi, BatchJobRequestsAreChecked) {
  auto r = post("/api/jobs/validate", R"({"names": []})");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400) << r->body;
  r = post("/api/jobs/validate", R"({"names": ["ggx", "nope_1", "nope_2"]})");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404) << r->body;
  EXPECT_EQ(bodyJson(r)["names"], json({"nope_1", "nope_2"})) << r->body;
  EXPECT_NE(r->body.find("nope_1"), std::string::npos);
  for (const char* b : {"{}", R"({"all": false})", R"({"names": "ggx"})", R"({"names": [1]})", "[]", "{x"}) {
    r = post("/api/jobs/validate", b);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << b << ": " << r->body;
  }
  r = get("/api/jobs/no-such-job");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404);

  // A named job with a BRDF that compiles and one that does not.
  r = put("/api/brdfs/job_good", kLambertWhite, "text/plain");
  ASSERT_TRUE(r && (r->status == 201 || r->status == 200));
  r = post("/api/jobs/validate", R"({"names": ["job_good", "lambert"]})");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  json accepted = bodyJson(r);
  EXPECT_EQ(accepted["total"], 2);
  json job;
  for (auto deadline = Clock::now() + std::chrono::seconds(60); Clock::now() < deadline;) {
    job = bodyJson(get("/api/jobs/" + accepted["id"].get<std::string>()));
    if (job["state"] == "done") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(job["state"], "done") << job.dump();
  ASSERT_EQ(job["results"].size(), 2u);
  for (const json& res : job["results"]) {
    EXPECT_EQ(res["errors"], 0) << res.dump();
    EXPECT_TRUE(res["compile_ms"].is_number());
    EXPECT_TRUE(res["log"].is_array());
    EXPECT_TRUE(res["checks"].is_object());
  }
}

// A file in the BRDFA Engine's format, as that engine's shaders/brdfs/*.brdf are written: bare
// GLSL, its own #define PI, render() reading the skybox, a slider and the object's texture.
constexpr const char* kEngineStyle = R"(#define PI 3.14159265359

vec3 lambert_engine(vec3 L, vec3 N, vec2 uv) {
    vec3 k_d = texture(iTexture0, uv).rgb;
    return k_d * max(dot(L, N), 0.) / PI;
}

vec3 render(vec3 L, vec3 N, vec3 V, vec2 textureCord, mat3 worldToLocal){
	vec3 envC = texture(skybox, L).rgb;
	return envC * lambert_engine(L, N, textureCord) * 2. * PI * iParameter2;
}
)";

TEST_F(LibraryApi, BrdfaEngineFileIsSavedAsLegacyRendersAndIsNotAnalysed) {
  auto r = put("/api/brdfs/engine_style", kEngineStyle, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_TRUE(r->status == 201 || r->status == 200) << r->body;
  json saved = bodyJson(r);
  EXPECT_EQ(saved["format"], "legacy");
  ASSERT_EQ(saved["params"].size(), 1u) << r->body;
  EXPECT_EQ(saved["params"][0]["name"], "iParameter2");
  EXPECT_EQ(saved["params"][0]["min"], 0.0);
  EXPECT_EQ(saved["params"][0]["max"], 1.0);

  // The engine's plain average of render() over uniform directions: here 2 pi f cos with a
  // white Lambertian in the furnace, so the mean is iParameter2 (set to 0.8), up to noise.
  EXPECT_NEAR(furnaceMean("engine_style", "iParameter2", 0.8), 0.8, 0.01);

  // The batch test compiles it and says why it has no numeric checks.
  r = post("/api/jobs/validate", R"({"names": ["engine_style"]})");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string id = bodyJson(r)["id"].get<std::string>();
  json job;
  for (auto deadline = Clock::now() + std::chrono::seconds(60); Clock::now() < deadline;) {
    job = bodyJson(get("/api/jobs/" + id));
    if (job["state"] == "done") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(job["state"], "done") << job.dump();
  const json& res = job["results"][0];
  EXPECT_EQ(res["ok"], true) << res.dump();
  EXPECT_EQ(res["errors"], 0) << res.dump();
  EXPECT_EQ(res["checks"]["error"], "unsupported") << res.dump();
}

// The engine's host shader defined PI and LI (`#define PI 3.14159265359`,
// `#define LI 8.`) before the file's text, and some of its files use them without defining
// them. Such a file is accepted and renders as the engine rendered it.
constexpr const char* kEngineStyleUsingHostNames = R"(vec3 lit_lambert(vec3 L, vec3 N, vec3 k_d) {
    return LI * k_d * max(dot(L, N), 0.) / PI;
}

vec3 render(vec3 L, vec3 N, vec3 V, vec2 textureCord, mat3 worldToLocal){
	vec3 envC = texture(skybox, L).rgb;
	return envC * lit_lambert(L, N, vec3(iParameter1));
}
)";

TEST_F(LibraryApi, BrdfaEngineFileUsingTheHostsPiAndLiRendersAsTheEngineWould) {
  auto r = put("/api/brdfs/engine_host_names", kEngineStyleUsingHostNames, "text/plain");
  ASSERT_TRUE(r);
  ASSERT_TRUE(r->status == 201 || r->status == 200) << r->body;
  EXPECT_EQ(bodyJson(r)["format"], "legacy");

  // The plain average of LI k_d cos / PI over uniform directions in the furnace:
  // LI k_d / (2 PI) = 8 * 0.75 / (2 pi) = 3 / pi, to 1% (measured: 0.03%).
  EXPECT_NEAR(furnaceMean("engine_host_names", "iParameter1", 0.75), 3.0 / 3.14159265358979323846, 0.0095);
}

TEST_F(LibraryApi, BatchJobOverAllRunsWhileTheStreamKeepsDelivering) {
  // A scene that never converges, so the stream has new frames all along.
  auto r = put("/api/sessions/default/scene", furnaceScene("lambert", json::object(), 32, 1 << 20, 1).dump());
  ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "");
  // A tab's scratch copy is listed but is no library entry: "all" leaves it out.
  r = put("/api/brdfs/scratch-itest", readRepoFile("shaders/brdfs/lambert.brdf"), "text/plain");
  ASSERT_TRUE(r && r->status == 201) << (r ? r->body : "");
  size_t brdfCount = bodyJson(get("/api/brdfs")).size() - 1;

  std::atomic<int> parts{0};
  std::atomic<bool> stopStream{false};
  std::thread streamer([&] {
    auto cli = server_->client(20);
    std::string buf;
    cli->Get("/api/sessions/default/stream", httplib::Headers{}, [&](const char* data, size_t len) {
      buf.append(data, len);
      for (size_t p; (p = buf.find("--frame\r\n")) != std::string::npos;) {
        ++parts;
        buf.erase(0, p + 9);
      }
      if (buf.size() > 8) buf.erase(0, buf.size() - 8);  // a boundary may span two chunks
      return !stopStream.load();
    });
  });
  // The stream is running before the job starts.
  for (auto deadline = Clock::now() + std::chrono::seconds(30); parts < 1 && Clock::now() < deadline;)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_GE(parts.load(), 1);

  r = post("/api/jobs/validate", R"({"all": true})");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  int partsAtSubmit = parts;
  json accepted = bodyJson(r);
  EXPECT_EQ(accepted["total"], brdfCount);
  std::string id = accepted["id"];
  json job;
  int partsDuringJob = 0;
  double lastProgress = 0;
  for (auto deadline = Clock::now() + std::chrono::seconds(120); Clock::now() < deadline;) {
    job = bodyJson(get("/api/jobs/" + id));
    ASSERT_TRUE(job.is_object());
    double progress = job["progress"];
    EXPECT_GE(progress, lastProgress);
    EXPECT_LE(progress, 1.0);
    lastProgress = progress;
    partsDuringJob = parts - partsAtSubmit;
    if (job["state"] == "done") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  stopStream = true;
  streamer.join();
  ASSERT_EQ(job["state"], "done") << job.dump();
  EXPECT_EQ(job["progress"], 1.0);
  ASSERT_EQ(job["results"].size(), brdfCount);
  std::set<std::string> names;
  for (const json& res : job["results"]) {
    names.insert(res["name"].get<std::string>());
    for (const char* key : {"name", "ok", "errors", "log", "compile_ms", "checks"})
      EXPECT_TRUE(res.contains(key)) << key << " missing: " << res.dump();
    // Built-ins compile; the check either reports numbers or says why it could not run.
    const json& checks = res["checks"];
    EXPECT_TRUE(checks.contains("error") ||
                (checks.contains("nan") && checks.contains("max_albedo") && checks.contains("max_reciprocity_error")))
        << res.dump();
  }
  EXPECT_EQ(names.size(), brdfCount);
  EXPECT_EQ(names.count("scratch-itest"), 0u);
  del("/api/brdfs/scratch-itest");
  std::fprintf(stderr, "batch over %zu BRDFs: %d stream parts arrived meanwhile\n", brdfCount, partsDuringJob);
  EXPECT_GE(partsDuringJob, 2) << "the stream stalled while the job ran";
}

// Every built-in keeps what it claims, with zero NaN/Inf, and ggx's albedo
// stays <= 1 down to roughness 0.001; a file that claims what it does not keep fails, and its
// log names the worst case.
TEST_F(LibraryApi, BatchTestOfEveryBuiltinHoldsItsClaims) {
  const std::string frame =
      "analytic\n::begin parameters\nfloat k 0 1 0.5\n::end parameters\n::begin shader\n"
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n  return ";
  auto r = put("/api/brdfs/claims_reciprocity",
               "# claims: reciprocity, non-negativity\n" + frame +
                   "vec3(k + max(dot(N, V), 0.0)) / 3.14159265;\n}\n::end shader\n",
               "text/plain");
  ASSERT_TRUE(r && r->status == 201) << (r ? r->body : "");
  r = put("/api/brdfs/claims_energy",
          "# claims: energy-conservation\n" + frame + "vec3((0.5 + k) / 3.14159265);\n}\n::end shader\n", "text/plain");
  ASSERT_TRUE(r && r->status == 201) << (r ? r->body : "");
  json names = json::array();
  for (const json& b : bodyJson(get("/api/brdfs")))
    if (b["builtin"] == true) names.push_back(b["name"]);
  ASSERT_GE(names.size(), 27u);
  names.push_back("claims_reciprocity");
  names.push_back("claims_energy");
  r = post("/api/jobs/validate", json{{"names", names}}.dump());
  ASSERT_TRUE(r && r->status == 202) << (r ? r->body : "");
  const std::string id = bodyJson(r)["id"];
  json job;
  for (auto deadline = Clock::now() + std::chrono::seconds(600); Clock::now() < deadline;) {
    job = bodyJson(get("/api/jobs/" + id));
    if (job["state"] == "done") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_EQ(job["state"], "done") << job.dump();
  for (const json& res : job["results"]) {
    const std::string name = res["name"];
    const json& c = res["checks"];
    std::string claims;
    for (const json& claim : c["claims"])
      claims += std::string(claim["claimed"] == true ? (claim["holds"] == true ? " +" : " !") : " ") +
                claim["name"].get<std::string>();
    std::fprintf(stderr, "%-24s ok %-5s max albedo %.4f +- %.4f  reciprocity %.2e  NaN %d  claims%s\n", name.c_str(),
                 res["ok"] == true ? "yes" : "NO", c.value("max_albedo", -1.0), c.value("max_albedo_std_error", -1.0),
                 c.value("max_reciprocity_error", -1.0), c.value("nan", -1), claims.c_str());
    if (name.rfind("claims_", 0) == 0) {
      EXPECT_EQ(res["ok"], false) << res.dump();
      std::string log;
      for (const json& line : res["log"]) log += line.get<std::string>() + "\n";
      const std::string claim = name == "claims_energy" ? "energy-conservation" : "reciprocity";
      EXPECT_NE(log.find("check: claim '" + claim + "' violated"), std::string::npos) << log;
      EXPECT_NE(log.find("k = 1 (others at their defaults)"), std::string::npos) << log;  // the worst case, named
      EXPECT_NE(log.find("at V (theta"), std::string::npos) << log;
      continue;
    }
    EXPECT_EQ(res["ok"], true) << res.dump();
    EXPECT_EQ(c["nan"], 0) << name;
    EXPECT_EQ(c["inf"], 0) << name;
    EXPECT_EQ(c["claims_declared"], true) << name;
    for (const json& claim : c["claims"]) {
      if (claim["claimed"] == true) {
        EXPECT_EQ(claim["holds"], true) << name << ": " << claim.dump();
      }
    }
    if (name == "ggx") {
      EXPECT_LE(c["max_albedo"].get<double>(), 1.0) << c.dump();
    }
  }
  del("/api/brdfs/claims_reciprocity");
  del("/api/brdfs/claims_energy");
}

}  // namespace
}  // namespace brdfa::itest
