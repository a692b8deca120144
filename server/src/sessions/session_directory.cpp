#include "sessions/session_directory.h"

#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "sessions/session_manager.h"
#include "util/atomic_file.h"

namespace brdfa::server {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

int64_t unixMillis() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string field(const json& j, const char* key) {
  auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::string();
}

}  // namespace

SessionDirectory::SessionDirectory(std::string dataDir, std::string replica,
                                   std::function<std::vector<std::shared_ptr<Session>>()> snapshot)
    : dir_((fs::path(dataDir) / "live").string()), replica_(std::move(replica)), snapshot_(std::move(snapshot)) {}

SessionDirectory::~SessionDirectory() { stop(); }

std::string SessionDirectory::filePath(const std::string& replica) const {
  return (fs::path(dir_) / (replica + ".json")).string();
}

void SessionDirectory::start() {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  // The files hold view keys, which read streams without a token: the folder is the server's.
  ::chmod(dir_.c_str(), 0700);
  removeStaleTempFiles(dir_);
  publish();
  thread_ = std::thread([this] {
    std::unique_lock lock(mutex_);
    while (!wake_.wait_for(lock, kHeartbeat, [this] { return stopping_; })) {
      lock.unlock();
      publish();
      lock.lock();
    }
  });
}

void SessionDirectory::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard writer(publishMutex_);
  removed_ = true;
  std::error_code ec;
  fs::remove(filePath(replica_), ec);
}

void SessionDirectory::publish() {
  std::lock_guard writer(publishMutex_);
  if (removed_) return;  // stopped: a late create or remove must not bring the file back
  json sessions = json::array();
  for (const std::shared_ptr<Session>& s : snapshot_()) {
    if (s->id() == kDefaultSessionId) continue;  // every replica has its own `default`
    const SessionOwnership& o = s->ownership();
    sessions.push_back({{"id", s->id()}, {"owner", o.user}, {"display_name", o.displayName}, {"view_key", o.viewKey}});
  }
  const json record{{"replica", replica_}, {"updated_unix_ms", unixMillis()}, {"sessions", std::move(sessions)}};
  Result<void> written = writeFileAtomically(filePath(replica_), record.dump() + "\n");
  if (!written && !warned_) {
    std::fprintf(stderr, "warning: cannot publish this replica's sessions in %s: %s\n", dir_.c_str(),
                 written.error().message.c_str());
    warned_ = true;
  }
}

std::vector<RemoteSession> SessionDirectory::others() const {
  std::vector<std::pair<int64_t, RemoteSession>> found;
  const int64_t now = unixMillis();
  std::error_code ec;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& p = it->path();
    if (p.extension() != ".json" || p.stem().string() == replica_) continue;
    std::ifstream in(p, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    const json j = json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
    if (!j.is_object()) continue;
    auto updated = j.find("updated_unix_ms");
    // A replica that stopped publishing is gone, and its sessions with it.
    if (updated == j.end() || !updated->is_number_integer() ||
        now - updated->get<int64_t>() > std::chrono::milliseconds(kStaleAfter).count())
      continue;
    const std::string replica = field(j, "replica");
    auto list = j.find("sessions");
    if (replica != p.stem().string() || list == j.end() || !list->is_array()) continue;
    for (const json& s : *list) {
      if (!s.is_object()) continue;
      RemoteSession r{field(s, "id"), replica, {field(s, "owner"), field(s, "display_name"), field(s, "view_key")}};
      // Only ids this replica could have made: a balancer routes them by their tag.
      if (r.id.rfind(replica + ".", 0) == 0) found.emplace_back(updated->get<int64_t>(), std::move(r));
    }
  }
  std::stable_sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<RemoteSession> out;
  for (auto& [stamp, r] : found) out.push_back(std::move(r));
  return out;
}

}  // namespace brdfa::server
