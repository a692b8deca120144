// The hostile corpus (tests/hostile/) against a real server. Each attack must get its
// documented answer, and the server must stay healthy and keep serving others meanwhile.
#include <cmath>
#include <atomic>
#include <thread>

#include "server_fixture.h"

namespace brdfa::itest {
namespace {

// A server with a short compile budget, so the attacks end quickly.
class Hostile : public ServerTest {
 protected:
  static void SetUpTestSuite() {
    server_ = std::make_unique<ServerProcess>();
    startError_ = server_->start({"--idle-timeout", "3", "--compile-timeout", "2", "--compile-memory", "512"});
  }
};

TEST_F(Hostile, MacroBombIsRefusedAtTheCompileBudgetWhileOtherCompilesGoOn) {
  const std::string bomb = readRepoFile("tests/hostile/macro_bomb.brdf");
  ASSERT_FALSE(bomb.empty());
  const std::string lambert = readRepoFile("shaders/brdfs/lambert.brdf");
  ASSERT_FALSE(lambert.empty());

  std::atomic<int> order{0};
  int bombDoneAt = 0, otherDoneAt = 0;
  int bombStatus = 0;
  std::string bombBody;
  std::thread attacker([&] {
    auto client = server_->client(60);
    auto r = client->Post("/api/brdfs/validate", bomb, "text/plain");
    bombDoneAt = ++order;
    if (r) bombStatus = r->status, bombBody = r->body;
  });
  // Let the bomb reach a worker, then compile something ordinary beside it. (A program not
  // compiled before: the SPIR-V cache must not answer for the compiler.)
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  auto other = post("/api/brdfs/validate", lambert + "\n// a hostile test's variant\n", "text/plain");
  otherDoneAt = ++order;
  attacker.join();

  ASSERT_TRUE(other);
  EXPECT_EQ(other->status, 200) << other->body;
  EXPECT_FALSE(bodyJson(other).value("cached", true)) << "the ordinary program must really compile";
  EXPECT_LT(otherDoneAt, bombDoneAt) << "an ordinary compile waited behind the bomb";

  EXPECT_EQ(bombStatus, 422) << bombBody;
  const nlohmann::json error = nlohmann::json::parse(bombBody, nullptr, false);
  ASSERT_TRUE(error.is_object()) << bombBody;
  EXPECT_EQ(error.value("error", ""), "compile_error");
  EXPECT_NE(error.value("message", "").find("exceeds the compile budget of 2 s / 512 MiB"), std::string::npos)
      << error.dump();
  ASSERT_TRUE(error.contains("diagnostics") && !error["diagnostics"].empty());

  // The killed worker is replaced: compiling still works, and so does the bomb's refusal.
  auto again = post("/api/brdfs/validate", lambert + "\n// once more\n", "text/plain");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 200) << again->body;
}

TEST_F(Hostile, UserCodeCannotReachTheIntegratorsResources) {
  struct Case {
    const char* file;
    int line;              // of the first diagnostic; 0: not checked
    const char* fragment;  // in the message or a diagnostic
  };
  for (const Case& c :
       {Case{"names_accumulators.brdf", 7, "brdfa_accum"},
        Case{"own_buffer_on_accumulators.brdf", 6, "set 0, binding 3, which the integrator already uses"},
        Case{"shared_memory_and_barrier.brdf", 0, "shared memory"},
        Case{"shared_memory_and_barrier.brdf", 0, "a barrier"},
        Case{"unused_slot.brdf", 5, "set 0, binding 1, which the pipeline layout does not have"}}) {
    const std::string text = readRepoFile(std::string("tests/hostile/") + c.file);
    ASSERT_FALSE(text.empty()) << c.file;
    for (const char* route : {"/api/brdfs/validate", "/api/brdfs/hostile_resource"}) {
      auto r = route[11] == 'v' ? post(route, text, "text/plain") : put(route, text, "text/plain");
      ASSERT_TRUE(r);
      EXPECT_EQ(r->status, 422) << c.file << " " << route << ": " << r->body;
      const nlohmann::json e = bodyJson(r);
      ASSERT_TRUE(e.contains("diagnostics") && !e["diagnostics"].empty()) << r->body;
      if (c.line) {
        EXPECT_EQ(e["diagnostics"][0].value("line", -1), c.line) << c.file << ": " << r->body;
      }
      EXPECT_NE(r->body.find(c.fragment), std::string::npos) << c.file << ": " << r->body;
    }
  }
  EXPECT_EQ(get("/api/brdfs/hostile_resource")->status, 404) << "a refused BRDF must not be stored";
}

// A server with a small memory budget: after what its processes hold at start, room for small
// views only.
class MemoryBudget : public ServerTest {
 protected:
  static void SetUpTestSuite() {
    server_ = std::make_unique<ServerProcess>();
    startError_ = server_->start({"--idle-timeout", "3", "--max-memory", "768"});
  }
};

TEST_F(MemoryBudget, AViewPastTheBudgetIsRefusedWith507AndOthersGoOn) {
  auto created = post("/api/sessions", R"({"render": {"width": 128, "height": 128}})");
  ASSERT_TRUE(created);
  ASSERT_EQ(created->status, 201) << created->body;
  const std::string id = bodyJson(created).value("id", "");
  auto frame = get("/api/sessions/" + id + "/frame?min_spp=1&format=pfm");
  ASSERT_TRUE(frame);
  ASSERT_EQ(frame->status, 200) << frame->body.substr(0, 300);
  auto health = get("/api/health");
  const nlohmann::json memory = bodyJson(health)["memory"];
  EXPECT_EQ(memory.value("budget_bytes", 0ull), 768ull << 20) << memory.dump();
  const uint64_t before = memory.value("render_targets_bytes", 0ull);
  EXPECT_GT(before, 0u);
  EXPECT_LE(memory.value("used_bytes", 0ull), 768ull << 20);

  // 2048 x 2048 needs ~600 MiB of render targets: refused, and says why.
  auto big = put("/api/sessions/" + id + "/scene", R"({"render": {"width": 2048, "height": 2048}})");
  ASSERT_TRUE(big);
  EXPECT_EQ(big->status, 507) << big->body.substr(0, 300);
  const nlohmann::json error = bodyJson(big);
  EXPECT_EQ(error.value("error", ""), "memory_budget") << big->body;
  EXPECT_NE(error.value("message", "").find("--max-memory 768 MiB"), std::string::npos) << big->body;
  // So is a one-shot render of that size, and a new session of it.
  auto oneShot = post("/api/render", R"({"scene": {"render": {"width": 2048, "height": 2048}}, "spp": 1})");
  ASSERT_TRUE(oneShot);
  EXPECT_EQ(oneShot->status, 507) << oneShot->body.substr(0, 300);

  // Nothing leaked: the refused views hold no memory, and the first session still renders its
  // old scene.
  EXPECT_EQ(bodyJson(get("/api/health"))["memory"].value("render_targets_bytes", 0ull), before);
  frame = get("/api/sessions/" + id + "/frame?min_spp=2&format=pfm");
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->status, 200);
  Image image;
  ASSERT_TRUE(decodeImage(frame->body, image));
  EXPECT_EQ(image.width, 128);
  auto again = put("/api/sessions/" + id + "/scene", R"({"render": {"width": 128, "height": 128}})");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->status, 200) << again->body.substr(0, 300);
  frame = get("/api/sessions/" + id + "/frame?min_spp=4&format=pfm");
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->status, 200);
  // Deleting the session gives its memory back.
  EXPECT_EQ(del("/api/sessions/" + id)->status, 204);
  EXPECT_LT(bodyJson(get("/api/health"))["memory"].value("render_targets_bytes", 0ull), before);
}

// Everything the renderer holds is in one budget; a view that only fits once unused cached
// programs are dropped gets them dropped, renders, and says so.
class MemoryBudgetShrink : public ServerTest {
 protected:
  static void SetUpTestSuite() {
    server_ = std::make_unique<ServerProcess>();
    // A budget where the test's view has to be at most 1024^2 (the per-pixel cost changes above
    // it) and the 11 programs still fit. A sanitized server process is larger (ASan's allocator
    // and shadow memory), which leaves less for views and programs: at 680 MiB the programs did
    // not fit there (1 MiB short), at 768 MiB the plain build's view came out at 1134^2.
    startError_ = server_->start({"--idle-timeout", "60", "--max-memory", kSanitizedBuild ? "768" : "680"});
  }
};

TEST_F(MemoryBudgetShrink, AViewThatFitsOnlyWithoutUnusedProgramsDropsThemAndSaysSo) {
  auto created = post("/api/sessions", furnaceScene("lambert", nlohmann::json::object(), 128, 4, 4).dump());
  ASSERT_TRUE(created);
  ASSERT_EQ(created->status, 201) << created->body;
  const std::string id = bodyJson(created).value("id", "");
  // Each BRDF builds a program; switching away leaves it cached and unused.
  for (const char* brdf : {"lambert", "ggx", "phong", "ward", "oren_nayar", "blinn_phong", "cook_torrance",
                           "ashikhmin_shirley", "lafortune", "disney_diffuse", "torrance_sparrow", "lambert"}) {
    auto r = put("/api/sessions/" + id + "/scene", furnaceScene(brdf, nlohmann::json::object(), 128, 4, 4).dump());
    ASSERT_TRUE(r && r->status == 200) << brdf << ": " << (r ? r->body : "no reply");
    auto frame = get("/api/sessions/" + id + "/frame?min_spp=1&format=pfm");
    ASSERT_TRUE(frame && frame->status == 200) << brdf;
  }
  const nlohmann::json before = bodyJson(get("/api/health"))["memory"];
  const nlohmann::json renderer = before["renderer"];
  const uint64_t budget = renderer.value("budget_bytes", 0ull);
  uint64_t used = 0;
  for (const char* use :
       {"process_bytes", "render_targets_bytes", "assets_bytes", "transfers_bytes", "programs_bytes", "compiles_bytes"})
    used += renderer.value(use, 0ull);
  const uint64_t targets128 = renderer.value("render_targets_bytes", 0ull);
  const uint64_t programs = renderer.value("programs_bytes", 0ull);
  ASSERT_GT(targets128, 0u) << before.dump();
  ASSERT_GT(programs, 40ull << 20) << "11 programs at ~4 MiB each: " << before.dump();
  ASSERT_LE(used, budget) << before.dump();
  EXPECT_LE(before.value("used_bytes", 0ull), before.value("budget_bytes", 0ull)) << before.dump();

  // A square view needing more than is left, but less than is left once the unused programs
  // (all but the one in use, ~4 MiB) are gone. Targets grow with the pixels (same per-pixel
  // cost up to 1024^2).
  const double perPixel = double(targets128) / (128.0 * 128.0);
  const double wanted = double(budget - (used - targets128)) + double(programs - (8ull << 20)) / 2;
  const int side = int(std::sqrt(wanted / perPixel));
  ASSERT_LE(side, 1024) << "the test assumes the per-pixel cost of views up to 1024^2";
  ASSERT_GT(double(side) * side * perPixel, double(budget - (used - targets128)) + (2 << 20))
      << "the view must not fit as things are";

  auto resized =
      put("/api/sessions/" + id + "/scene", furnaceScene("lambert", nlohmann::json::object(), side, 4, 4).dump());
  ASSERT_TRUE(resized);
  ASSERT_EQ(resized->status, 200) << side << "^2: " << resized->body.substr(0, 400);
  const nlohmann::json after = bodyJson(get("/api/health"))["memory"];
  EXPECT_GE(after["renderer"].value("drops", 0ull), 1u) << after.dump();
  EXPECT_LT(after["renderer"].value("programs_bytes", 0ull), programs) << after.dump();
  const std::string lastDropped = after["renderer"].value("last_dropped", "");
  EXPECT_NE(lastDropped.find("cached program"), std::string::npos) << lastDropped;
  EXPECT_LE(after.value("used_bytes", 0ull), after.value("budget_bytes", 0ull)) << after.dump();
  // The session says what was dropped for it, and renders at the new size.
  auto session = get("/api/sessions/" + id);
  ASSERT_TRUE(session && session->status == 200);
  bool said = false;
  for (const auto& w : bodyJson(session)["stats"].value("warnings", nlohmann::json::array()))
    said = said || w.get<std::string>().find("memory: dropped") != std::string::npos;
  EXPECT_TRUE(said) << session->body.substr(0, 600);
  auto frame = get("/api/sessions/" + id + "/frame?min_spp=1&format=pfm");
  ASSERT_TRUE(frame);
  ASSERT_EQ(frame->status, 200);
  Image image;
  ASSERT_TRUE(decodeImage(frame->body, image));
  EXPECT_EQ(image.width, side);
  // A dropped program is rebuilt when used again.
  auto back = put("/api/sessions/" + id + "/scene", furnaceScene("ggx", nlohmann::json::object(), 128, 4, 4).dump());
  ASSERT_TRUE(back && back->status == 200) << (back ? back->body : "");
  frame = get("/api/sessions/" + id + "/frame?min_spp=1&format=pfm");
  ASSERT_TRUE(frame && frame->status == 200);
  EXPECT_EQ(del("/api/sessions/" + id)->status, 204);
}

}  // namespace
}  // namespace brdfa::itest
