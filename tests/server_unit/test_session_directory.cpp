// The replicas' shared list of sessions, without a device: what one replica believes of the
// files that the others (or anyone who can write the folder) leave in <data>/live.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "sessions/session_directory.h"

namespace brdfa::server {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

int64_t nowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

class SessionDirectoryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("brdfa-live-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "live");
  }
  void TearDown() override { fs::remove_all(dir_); }
  void write(const std::string& file, const json& j) { std::ofstream(dir_ / "live" / file) << j.dump(); }
  static json entry(const std::string& id, const std::string& owner) {
    return {{"id", id}, {"owner", owner}, {"display_name", owner + " D"}, {"view_key", "key-" + id}};
  }
  std::unique_ptr<SessionDirectory> open(const std::string& replica) {
    return std::make_unique<SessionDirectory>(dir_.string(), replica,
                                              [] { return std::vector<std::shared_ptr<Session>>{}; });
  }
  fs::path dir_;
};

TEST_F(SessionDirectoryTest, ListsLiveReplicasSessionsWithOwnersAndKeys) {
  write("r2.json", {{"replica", "r2"}, {"updated_unix_ms", nowMs()}, {"sessions", {entry("r2.aa", "alice")}}});
  auto r1 = open("r1");
  std::vector<RemoteSession> others = r1->others();
  ASSERT_EQ(others.size(), 1u);
  EXPECT_EQ(others[0].id, "r2.aa");
  EXPECT_EQ(others[0].replica, "r2");
  EXPECT_EQ(others[0].ownership.user, "alice");
  EXPECT_EQ(others[0].ownership.displayName, "alice D");
  EXPECT_EQ(others[0].ownership.viewKey, "key-r2.aa");
}

TEST_F(SessionDirectoryTest, IgnoresItsOwnFileStaleFilesAndForgedEntries) {
  const int64_t now = nowMs();
  write("r1.json", {{"replica", "r1"}, {"updated_unix_ms", now}, {"sessions", {entry("r1.own", "alice")}}});
  // Stopped publishing longer ago than kStaleAfter: a crashed replica.
  write("r2.json", {{"replica", "r2"}, {"updated_unix_ms", now - 11'000}, {"sessions", {entry("r2.old", "alice")}}});
  // An id another replica's tag starts is not this file's to publish: a balancer would route it there.
  write(
      "r3.json",
      {{"replica", "r3"}, {"updated_unix_ms", now}, {"sessions", {entry("r1.forged", "bob"), entry("r3.ok", "bob")}}});
  // A file that names another replica than its own name.
  write("r4.json", {{"replica", "r5"}, {"updated_unix_ms", now}, {"sessions", {entry("r5.x", "bob")}}});
  write("r6.json", json::array());  // not an object
  std::ofstream(dir_ / "live" / "r7.json") << "{ half a file";
  write("r8.json", {{"replica", "r8"}, {"sessions", {entry("r8.nostamp", "bob")}}});
  auto r1 = open("r1");
  std::vector<RemoteSession> others = r1->others();
  ASSERT_EQ(others.size(), 1u);
  EXPECT_EQ(others[0].id, "r3.ok");
}

TEST_F(SessionDirectoryTest, PublishesUntilStoppedThenRemovesItsFile) {
  auto r1 = open("r1");
  r1->start();
  const fs::path own = dir_ / "live" / "r1.json";
  ASSERT_TRUE(fs::exists(own));
  struct stat st {};
  ASSERT_EQ(::stat((dir_ / "live").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u) << "the files hold view keys";
  auto r2 = open("r2");
  r2->start();
  EXPECT_TRUE(r1->others().empty()) << "r2 publishes no sessions";
  r1->stop();
  EXPECT_FALSE(fs::exists(own));
  r1->publish();  // a late change after the stop
  EXPECT_FALSE(fs::exists(own)) << "a stopped replica's file stays removed";
  r2->stop();
}

}  // namespace
}  // namespace brdfa::server
