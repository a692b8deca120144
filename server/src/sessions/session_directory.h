// The sessions of every replica that shares this data folder (docs/deploy.md, Replicas): each
// replica publishes who owns which of its sessions in <data>/live/<replica>.json, so that a
// listing through any replica (the teacher's Class tab) shows the whole class. Sessions stay in
// the memory of the replica that made them; only their ids, owners and view keys are published.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "sessions/session.h"

namespace brdfa::server {

// A session held by another replica, as that replica last published it.
struct RemoteSession {
  std::string id;
  std::string replica;
  SessionOwnership ownership;
};

class SessionDirectory {
 public:
  // How often a replica republishes (its heartbeat), and how old another's file may be before
  // that replica counts as gone (crashed, or killed before it could remove its file).
  static constexpr std::chrono::seconds kHeartbeat{2};
  static constexpr std::chrono::seconds kStaleAfter{10};

  // `snapshot` returns this replica's sessions; it is called from publish() and the heartbeat
  // thread, never under a lock of the directory's.
  SessionDirectory(std::string dataDir, std::string replica,
                   std::function<std::vector<std::shared_ptr<Session>>()> snapshot);
  ~SessionDirectory();  // stop()

  // Publishes now and then every kHeartbeat until stop().
  void start();
  // Ends the heartbeat and removes this replica's file: its sessions end with it.
  void stop();
  // Writes this replica's sessions now (after a create or a remove). A failed write is logged
  // once and retried by the heartbeat.
  void publish();

  // Sessions that the other live replicas hold, oldest publication first.
  std::vector<RemoteSession> others() const;

 private:
  std::string filePath(const std::string& replica) const;

  const std::string dir_;
  const std::string replica_;
  const std::function<std::vector<std::shared_ptr<Session>>()> snapshot_;
  std::mutex publishMutex_;  // one writer at a time, so an older snapshot never lands last
  bool warned_ = false;      // under publishMutex_
  bool removed_ = false;     // under publishMutex_: stop() removed the file
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace brdfa::server
