// What the HTTP front needs and cpp-httplib 0.11 lacks: a deadline for receiving
// each request, a cap on open connections per client address, and a way for a long handler to
// see that its client went away. httplib's own read timeout applies per recv(), so a client
// trickling a byte a second never trips it and keeps a worker thread for as long as it likes.
#pragma once

#include <httplib.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <cstddef>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace brdfa::server {

struct ConnectionLimits {
  size_t threads = 64;     // --threads: the worker pool
  int maxPerAddress = 32;  // --max-connections-per-address
  // --request-read-timeout: the request line and headers must arrive within this of the
  // connection's accept (or of the previous response, on a kept-alive connection); the body
  // within this of the headers, plus one second per kBodyMinBytesPerSecond received.
  std::chrono::milliseconds requestReadTimeout{10'000};
  // Told of each connection refused before its request was read (for /metrics' rejections).
  std::function<void(const char* reason)> onRefused;
};

// A body slower than this on average is cut (a 64 MiB upload gets 64 minutes).
inline constexpr size_t kBodyMinBytesPerSecond = 16 * 1024;

// The open connections, keyed by the peer's (address, port) as httplib reports them in
// Request::remote_addr / remote_port, so that a handler can find its own.
class ConnectionRegistry {
 public:
  explicit ConnectionRegistry(int maxPerAddress) : maxPerAddress_(maxPerAddress) {}

  // Registers an accepted socket. False, registering nothing, when `address` already has
  // maxPerAddress connections open.
  bool add(const std::string& address, int port, int fd);
  // Must come before the socket is closed: peerClosed() polls registered fds under the lock.
  void remove(const std::string& address, int port);

  // True once the client of that connection has closed or reset it (it sent FIN or RST; a
  // request it pipelined behind does not count). False for a connection not registered.
  bool peerClosed(const std::string& address, int port) const;

  int openFrom(const std::string& address) const;
  int maxPerAddress() const { return maxPerAddress_; }

 private:
  const int maxPerAddress_;
  mutable std::mutex mutex_;
  std::map<std::pair<std::string, int>, int> fds_;
  std::map<std::string, int> perAddress_;
};

// Closes refused sockets without a worker: keeps each for a short grace in which it drops what
// the client sends, so the client reads its 503 instead of a reset (closing a socket with
// unread input resets the connection), until the client closes or the grace ends.
class LingeringCloser {
 public:
  LingeringCloser();
  ~LingeringCloser();  // closes what is left
  void add(int fd);    // takes ownership of fd

 private:
  void run();
  std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<std::pair<int, std::chrono::steady_clock::time_point>> fds_;
  bool stop_ = false;
  std::thread thread_;
};

// httplib::Server whose connections go through the registry and the read deadlines. It owns
// the worker pool (`limits.threads`); leave new_task_queue alone.
// Called from a handler (the pre-routing gate) that answers without reading the request's body:
// the connection is closed after this response, so the unread body is never parsed as a request.
void closeAfterThisResponse();

class GuardedServer : public httplib::Server {
 public:
  explicit GuardedServer(const ConnectionLimits& limits);

  ConnectionRegistry& connections() { return registry_; }

  // After binding: httplib listens with a backlog of 5, so a burst of connections (a page
  // load, or slow clients) has the kernel drop SYNs and clients retry after 1 s, 3 s, ...
  bool widenBacklog(int backlog);

 private:
  // httplib 0.11 runs this on a worker for every accepted socket (private virtual: overriding
  // it is allowed, calling the base one is not, so this is the whole keep-alive loop).
  bool process_and_close_socket(socket_t sock) override;
  // Over the per-address cap: a 503 without reading the request, then a lingering close.
  void refuse(socket_t sock, const std::string& address);

  ConnectionLimits limits_;
  ConnectionRegistry registry_;
  LingeringCloser closer_;
};

}  // namespace brdfa::server
