// Library, preset and BRDF operations racing from many clients. Eight clients send a
// random mix of PUT/GET/DELETE of two BRDF names and of their presets for a bounded time
// (BRDFA_RACE_SECONDS, 30 by default; `make soak` runs 600). Every reply must be one of the
// documented statuses of its route, the server must stay up, and afterwards a re-created BRDF
// must start without presets (none may outlive its BRDF).
#include <atomic>
#include <cstdlib>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "server_fixture.h"

namespace brdfa::itest {
namespace {

class Races : public ServerTest {};

const char* const kSource =
    "analytic\n::begin parameters\nfloat albedo 0 1 0.5\n::end parameters\n"
    "::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(albedo / 3.14159265); }\n"
    "::end shader\n";

int raceSeconds() {
  const char* env = std::getenv("BRDFA_RACE_SECONDS");
  int s = env ? std::atoi(env) : 30;
  return s > 0 ? s : 30;
}

TEST_F(Races, MixedLibraryAndPresetTrafficFromEightClientsNeverCrashes) {
  const std::vector<std::string> names = {"race_a", "race_b"};
  // The documented statuses of each operation while others race on the same names.
  struct Op {
    const char* label;
    std::set<int> allowed;
  };
  const std::vector<Op> ops = {
      {"PUT brdf", {200, 201}},        {"GET brdf", {200, 404}},   {"DELETE brdf", {204, 404}},
      {"PUT preset", {200, 201, 404}}, {"GET preset", {200, 404}}, {"DELETE preset", {204, 404}},
      {"GET presets", {200, 404}},
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(raceSeconds());
  std::mutex failuresMutex;
  std::vector<std::string> failures;
  std::map<std::string, int> counts;
  std::atomic<long> requests{0};
  auto worker = [&](unsigned seed) {
    auto client = server_->client(30);
    // One kept-alive connection per client, as a browser or script holds: eight clients, eight
    // connections (a new one per request piled up past the per-address cap of 32 on a loaded
    // machine, while the server's side of the closed ones was still being let go).
    client->set_keep_alive(true);
    std::mt19937 rng(seed);
    while (std::chrono::steady_clock::now() < deadline) {
      const std::string name = names[rng() % names.size()];
      const size_t which = rng() % ops.size();
      const std::string preset = rng() % 2 ? "p1" : "p2";
      const std::string base = "/api/brdfs/" + name;
      auto send = [&]() -> httplib::Result {
        switch (which) {
          case 0: return client->Put(base, kSource, "text/plain");
          case 1: return client->Get(base);
          case 2: return client->Delete(base);
          case 3: return client->Put(base + "/presets/" + preset, R"({"albedo": 0.25})", "application/json");
          case 4: return client->Get(base + "/presets/" + preset);
          case 5: return client->Delete(base + "/presets/" + preset);
          default: return client->Get(base + "/presets");
        }
      };
      httplib::Result r = send();
      ++requests;
      std::lock_guard lock(failuresMutex);
      if (!r) {
        failures.push_back(std::string(ops[which].label) + " " + name + ": no reply (" + httplib::to_string(r.error()) +
                           ")");
        return;  // the server may be gone: stop this client
      }
      ++counts[std::string(ops[which].label) + " " + std::to_string(r->status)];
      if (!ops[which].allowed.count(r->status) && failures.size() < 20)
        failures.push_back(std::string(ops[which].label) + " " + name + ": " + std::to_string(r->status) + " " +
                           r->body.substr(0, 200));
    }
  };
  std::vector<std::thread> clients;
  for (unsigned i = 0; i < 8; ++i) clients.emplace_back(worker, 1234u + i);
  for (std::thread& t : clients) t.join();
  for (const std::string& f : failures) ADD_FAILURE() << f;
  std::string summary;
  for (const auto& [what, n] : counts) summary += "  " + what + ": " + std::to_string(n) + "\n";
  std::printf("%ld requests in %d s\n%s", requests.load(), raceSeconds(), summary.c_str());
  // Each kind of operation really ran, both ways where it can go both ways.
  for (const char* seen :
       {"PUT brdf 201", "DELETE brdf 204", "PUT preset 201", "PUT preset 404", "GET preset 200", "DELETE preset 204"})
    EXPECT_GT(counts[seen], 0) << seen << " never happened: the race did not race";

  // Quiet now: a BRDF deleted and created again starts without presets.
  for (const std::string& name : names) {
    del("/api/brdfs/" + name);
    auto created = put("/api/brdfs/" + name, kSource, "text/plain");
    ASSERT_TRUE(created);
    EXPECT_EQ(created->status, 201) << created->body;
    auto presets = get("/api/brdfs/" + name + "/presets");
    ASSERT_TRUE(presets);
    EXPECT_EQ(bodyJson(presets), nlohmann::json::array()) << name << " inherited presets";
    del("/api/brdfs/" + name);
  }
}

}  // namespace
}  // namespace brdfa::itest
