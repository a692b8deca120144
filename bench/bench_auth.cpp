// Authentication's cost per request, as a ratio against `none` measured in one run: two servers
// (none; tokens with a student's token), one keep-alive client each, rounds interleaved so that
// machine noise hits both alike. The request is a light one (a session's stats), so the
// identity lookup is as large a part of it as it can be.
#include "bench_auth.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include <unistd.h>

#include "server_process.h"

namespace brdfa::bench {

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kRequestsPerRound = 400;
constexpr const char* kPath = "/api/sessions/default/stats";

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// Median microseconds of one GET over `kRequestsPerRound` on `cli`; negative on a failure.
double roundMicros(httplib::Client& cli, const httplib::Headers& headers) {
  std::vector<double> us;
  us.reserve(kRequestsPerRound);
  for (int i = 0; i < kRequestsPerRound; ++i) {
    const auto t0 = Clock::now();
    auto r = cli.Get(kPath, headers);
    if (!r || r->status != 200) return -1;
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
  }
  return median(us);
}

}  // namespace

int runAuthBench(const std::string& serverBinary, const std::string& sourceDir, int rounds) {
  const std::string tokenFile = "/tmp/brdfa-bench-admin-" + std::to_string(::getpid());
  const std::string admin = "bench-admin-token-0123456789abcdef";
  std::ofstream(tokenFile) << admin << "\n";
  testsupport::ServerProcess none, tokens;
  if (std::string err = none.start(serverBinary, sourceDir, {"--auth", "none"}); !err.empty()) {
    std::fprintf(stderr, "auth bench: %s\n", err.c_str());
    return 1;
  }
  if (std::string err = tokens.start(serverBinary, sourceDir, {"--auth", "tokens", "--admin-token-file", tokenFile});
      !err.empty()) {
    std::fprintf(stderr, "auth bench: %s\n", err.c_str());
    return 1;
  }
  std::remove(tokenFile.c_str());
  auto noneCli = none.client(30), tokensCli = tokens.client(30);
  noneCli->set_keep_alive(true);
  tokensCli->set_keep_alive(true);
  noneCli->set_tcp_nodelay(true);  // else delayed ACKs, not the server, set the pace
  tokensCli->set_tcp_nodelay(true);
  auto made = tokensCli->Post("/api/auth/users", {{"Authorization", "Bearer " + admin}}, R"({"user": "bench-student"})",
                              "application/json");
  if (!made || made->status != 201) {
    std::fprintf(stderr, "auth bench: cannot make a student (%d)\n", made ? made->status : -1);
    return 1;
  }
  const std::string token = nlohmann::json::parse(made->body)["token"];
  const httplib::Headers student{{"Authorization", "Bearer " + token}};
  roundMicros(*noneCli, {});  // warm: the default scene is applied on first use
  roundMicros(*tokensCli, student);
  std::vector<double> noneUs, tokensUs, ratios;
  for (int r = 0; r < rounds; ++r) {
    const double a = roundMicros(*noneCli, {});
    const double b = roundMicros(*tokensCli, student);
    if (a <= 0 || b <= 0) {
      std::fprintf(stderr, "auth bench: a request failed\n");
      return 1;
    }
    noneUs.push_back(a);
    tokensUs.push_back(b);
    ratios.push_back(b / a);
  }
  std::printf("\n## Authentication per request (GET %s, keep-alive, %d rounds x %d requests)\n\n", kPath, rounds,
              kRequestsPerRound);
  std::printf("| mode | median per request (us) |\n|---|---|\n");
  std::printf("| none | %.1f |\n| tokens (student bearer token) | %.1f |\n", median(noneUs), median(tokensUs));
  std::printf("\ntokens / none: median ratio %.3f; cost %.1f us per request (target: under 1000 us)\n", median(ratios),
              median(tokensUs) - median(noneUs));
  return 0;
}

}  // namespace brdfa::bench
