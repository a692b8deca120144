// Connections: slow clients cannot take the workers, one address cannot take them
// all, and a one-shot render whose client left gives its slot back within a pass. Raw sockets,
// because httplib's client cannot trickle a request or hang up mid-render.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <thread>

#include "server_fixture.h"

namespace brdfa::itest {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// One response (headers and a Content-Length body) within `timeout`; "" when none came.
std::string readResponse(int fd, std::chrono::milliseconds timeout) {
  std::string got;
  const auto until = Clock::now() + timeout;
  while (Clock::now() < until) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    char buf[4096];
    ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    if (n <= 0) break;
    got.append(buf, static_cast<size_t>(n));
    size_t end = got.find("\r\n\r\n");
    if (end == std::string::npos) continue;
    size_t cl = got.find("Content-Length: ");
    size_t length = cl < end ? std::stoul(got.substr(cl + 16)) : 0;
    if (got.size() >= end + 4 + length) return got;
  }
  return got;
}

int statusOf(const std::string& response) {
  return response.rfind("HTTP/1.1 ", 0) == 0 ? std::atoi(response.c_str() + 9) : 0;
}

size_t countOf(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Few workers, a 2 s request deadline and no per-address cap to speak of: only the deadline
// stands between the slow clients and the pool.
class HostileSlowClients : public ServerTest {
 protected:
  static void SetUpTestSuite() {
    server_ = std::make_unique<ServerProcess>();
    startError_ = server_->start({"--idle-timeout", "3", "--threads", "16", "--request-read-timeout", "2",
                                  "--max-connections-per-address", "1000"});
  }
};

TEST_F(HostileSlowClients, SlowLorisConnectionsAreCutAtTheReadDeadline) {
  // 70 connections, more than the 16 workers, each sending its request a byte a second: with
  // httplib's per-recv timeout alone they would hold every worker for as long as they trickle.
  constexpr int kSlow = 70;
  const std::string request =
      "GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + std::string(40, 'z') + "\r\n\r\n";
  std::vector<int> fds;
  std::vector<Clock::time_point> openedAt;
  std::vector<double> closedAfter(kSlow, -1.0);
  const auto connecting = Clock::now();
  for (int i = 0; i < kSlow; ++i) {
    int fd = connectTo(server_->port());
    ASSERT_GE(fd, 0) << "connection " << i;
    fds.push_back(fd);
    openedAt.push_back(Clock::now());
    ASSERT_TRUE(sendAll(fd, request.substr(0, 1)));
  }
  const double connectSeconds = secondsSince(connecting);

  // Meanwhile an ordinary client asks for health on a fresh connection.
  std::atomic<bool> healthDone{false};
  int healthStatus = 0;
  double healthSeconds = -1;
  std::thread health([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    auto client = server_->client(12);
    const auto start = Clock::now();
    auto r = client->Get("/api/health");
    healthSeconds = secondsSince(start);
    if (r) healthStatus = r->status;
    healthDone = true;
  });

  // Trickle a byte a second on every connection still open, and note when each is closed.
  const auto start = Clock::now();
  size_t sent = 1;
  int open = kSlow;
  while (open > 0 && secondsSince(start) < 10) {
    if (secondsSince(start) >= static_cast<double>(sent)) {
      for (int i = 0; i < kSlow; ++i)
        if (closedAfter[i] < 0) (void)::send(fds[i], request.data() + sent, 1, MSG_NOSIGNAL);
      ++sent;
    }
    for (int i = 0; i < kSlow; ++i)
      if (closedAfter[i] < 0 && closedByServer(fds[i])) closedAfter[i] = secondsSince(openedAt[i]), --open;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  health.join();
  for (int fd : fds) ::close(fd);

  double first = 1e9, last = 0;
  for (double t : closedAfter)
    if (t >= 0) first = std::min(first, t), last = std::max(last, t);
  std::fprintf(stderr,
               "slow loris: %d connected in %.2f s; %d of them cut %.2f..%.2f s after opening; health (asked "
               "0.2 s after the last connected) answered %d in %.2f s\n",
               kSlow, connectSeconds, kSlow - open, first, last, healthStatus, healthSeconds);
  EXPECT_EQ(open, 0) << "connections still open after 10 s of trickling";
  // Cut at the 2 s deadline: not before it, and not long after (the connections queued behind
  // the first 16 were accepted at the same time, so their deadline had passed too).
  EXPECT_GE(first, 1.8);
  EXPECT_LE(last, 4.5);
  ASSERT_TRUE(healthDone);
  EXPECT_EQ(healthStatus, 200) << "health got no answer while slow clients held the workers";
  EXPECT_LT(healthSeconds, 4.5) << "health waited past the slow clients' deadline";
  EXPECT_GE(countOf(server_->logTail(200000), "request headers not received within the read deadline"), 60u);
}

TEST_F(HostileSlowClients, ABodyTrickledAfterItsHeadersIsCutToo) {
  const int fd = connectTo(server_->port());
  ASSERT_GE(fd, 0);
  const auto start = Clock::now();
  ASSERT_TRUE(sendAll(fd,
                      "POST /api/render HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
                      "Content-Length: 100\r\n\r\n{"));
  bool closed = false;
  while (!closed && secondsSince(start) < 8) {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    (void)::send(fd, " ", 1, MSG_NOSIGNAL);
    closed = closedByServer(fd);
  }
  const double after = secondsSince(start);
  ::close(fd);
  EXPECT_TRUE(closed) << "a body trickled at 2 bytes/s was still being read after 8 s";
  EXPECT_GE(after, 1.8);
  EXPECT_LE(after, 4.5);
  EXPECT_NE(server_->logTail().find("request body not received within the read deadline"), std::string::npos);
}

// Four connections per address at most.
class HostileConnectionCap : public ServerTest {
 protected:
  static void SetUpTestSuite() {
    server_ = std::make_unique<ServerProcess>();
    startError_ = server_->start({"--idle-timeout", "3", "--max-connections-per-address", "4"});
  }
};

TEST_F(HostileConnectionCap, TheConnectionPastThePerAddressCapIsRefusedAtOnce) {
  // Four connections, each with half a request sent: open, and counted.
  const std::string head = "GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\n";
  std::vector<int> fds;
  for (int i = 0; i < 4; ++i) {
    int fd = connectTo(server_->port());
    ASSERT_GE(fd, 0);
    ASSERT_TRUE(sendAll(fd, head));
    fds.push_back(fd);
  }
  // The fifth is answered 503 at once, with the JSON error body, once the server has taken the
  // four (a worker registers each when it starts on it: on a loaded machine that can take a
  // while, and a fifth that came first is served).
  auto askFifth = [&](double& seconds) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const auto start = Clock::now();
    auto r = server_->client(5)->Get("/api/health");
    seconds = secondsSince(start);
    return r;
  };
  double refusedIn = 0;
  auto fifth = askFifth(refusedIn);
  for (auto until = Clock::now() + std::chrono::seconds(5); fifth && fifth->status == 200 && Clock::now() < until;)
    fifth = askFifth(refusedIn);
  ASSERT_TRUE(fifth) << "no answer at all: " << httplib::to_string(fifth.error());
  EXPECT_EQ(fifth->status, 503) << fifth->body;
  EXPECT_EQ(bodyJson(fifth).value("error", ""), "too_many_connections") << fifth->body;
  EXPECT_LT(refusedIn, 1.0);

  // Another address has its own count.
  const int other = connectTo(server_->port(), "127.0.0.2");
  ASSERT_GE(other, 0);
  ASSERT_TRUE(sendAll(other, head + "Connection: close\r\n\r\n"));
  const std::string otherResponse = readResponse(other, std::chrono::seconds(5));
  ::close(other);
  EXPECT_EQ(statusOf(otherResponse), 200) << otherResponse.substr(0, 200);

  // The four were not harmed: each finishes its request and gets its answer.
  for (int fd : fds) {
    ASSERT_TRUE(sendAll(fd, "\r\n"));
    const std::string response = readResponse(fd, std::chrono::seconds(5));
    EXPECT_EQ(statusOf(response), 200) << response.substr(0, 200);
  }

  // Closing one makes room for a new one, while the other three stay open.
  ::close(fds.back());
  fds.pop_back();
  int status = 0;
  auto start = Clock::now();
  while (status != 200 && secondsSince(start) < 3) {
    auto r = server_->client(5)->Get("/api/health");
    status = r ? r->status : 0;
    if (status != 200) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::fprintf(stderr, "connection cap: fifth refused in %.3f s; room again %.3f s after a close\n", refusedIn,
               secondsSince(start));
  EXPECT_EQ(status, 200) << "a closed connection still counts against the cap";
  for (int fd : fds) ::close(fd);
  // Let the server see the closes before the fixture's own health check.
  for (start = Clock::now(); secondsSince(start) < 3;) {
    auto r = server_->client(5)->Get("/api/health");
    if (r && r->status == 200) break;
  }
}

// Default limits: two one-shot renders at a time.
class HostileAbandonedRender : public ServerTest {};

TEST_F(HostileAbandonedRender, AOneShotWhoseClientLeftGivesItsSlotBackWithinAPass) {
  // Compile the BRDF's pipeline first, so the timings below are of rendering alone.
  const nlohmann::json small = {
      {"scene", furnaceScene("lambert", nlohmann::json::object(), 32, 4, 4)}, {"spp", 4}, {"format", "pfm"}};
  auto warm = post("/api/render", small.dump());
  ASSERT_TRUE(warm);
  ASSERT_EQ(warm->status, 200) << warm->body.substr(0, 300);

  // Two renders that would take minutes (65536 samples, 4 a pass, 256 x 256) take both slots;
  // their clients hang up after half a second.
  const nlohmann::json huge = {
      {"scene", furnaceScene("lambert", nlohmann::json::object(), 256, 65536, 4)}, {"spp", 65536}, {"format", "pfm"}};
  const std::string body = huge.dump();
  const std::string request =
      "POST /api/render HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
      "Content-Length: " +
      std::to_string(body.size()) + "\r\n\r\n" + body;
  int a = connectTo(server_->port()), b = connectTo(server_->port());
  ASSERT_GE(a, 0);
  ASSERT_GE(b, 0);
  ASSERT_TRUE(sendAll(a, request));
  ASSERT_TRUE(sendAll(b, request));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ::close(a);
  ::close(b);

  // A third one-shot gets a slot within about a pass, not after the abandoned ones finish.
  const auto start = Clock::now();
  auto third = server_->client(20)->Post("/api/render", small.dump(), "application/json");
  const double waited = secondsSince(start);
  ASSERT_TRUE(third) << httplib::to_string(third.error());
  EXPECT_EQ(third->status, 200) << third->body.substr(0, 300);
  EXPECT_LT(waited, 5.0);

  // And the log says why: both renders stopped when their clients left.
  size_t stopped = 0;
  for (auto until = Clock::now() + std::chrono::seconds(3); Clock::now() < until;) {
    stopped = countOf(server_->logTail(200000), "closed the connection; one-shot render stopped");
    if (stopped >= 2) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::fprintf(stderr, "abandoned renders: third one-shot answered %d in %.2f s\n", third->status, waited);
  EXPECT_EQ(stopped, 2u) << server_->logTail(3000);
}

}  // namespace
}  // namespace brdfa::itest
