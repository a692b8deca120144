#include "http/connection_guard.h"

#include <utility>
#include <netdb.h>
#include <poll.h>
#include <pthread.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <vector>

#include "http/http_errors.h"

namespace brdfa::server {

namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// Longest single wait: every wait wakes this often to notice that the server is stopping.
constexpr milliseconds kWaitSlice{100};
// A refused connection is kept this long at most for its client to read the 503 and close.
constexpr milliseconds kRefusalGrace{1000};
// Refused sockets lingering at once; past it they are closed at once (bounds the fds held).
constexpr size_t kMaxLingering = 256;

// When the listener accepted the socket this worker is about to serve (see StampingQueue).
thread_local Clock::time_point tAcceptedAt{};
// Set by closeAfterThisResponse() while a request of this worker's connection is handled.
thread_local bool tCloseAfterResponse = false;

// httplib 0.11 enqueues one task per accepted socket, on the listener thread right after
// accept(). Stamping the time there lets the request deadline count from the accept, so a
// connection that waited in the queue behind slow ones gets no fresh allowance of its own:
// once the slow ones are cut, the queue drains at once.
class StampingQueue : public httplib::TaskQueue {
 public:
  explicit StampingQueue(size_t threads) : pool_(threads) {}
  void enqueue(std::function<void()> fn) override {
    pool_.enqueue([fn = std::move(fn), at = Clock::now()] {
      // The pool's threads, named once for top, perf and the bench's CPU breakdown.
      static thread_local bool named = (::pthread_setname_np(::pthread_self(), "brdfa-http"), true);
      (void)named;
      tAcceptedAt = at;
      fn();
    });
  }
  void shutdown() override { pool_.shutdown(); }

 private:
  httplib::ThreadPool pool_;
};

int pollOne(int fd, short events, milliseconds wait) {
  pollfd p{fd, events, 0};
  int n = ::poll(&p, 1, static_cast<int>(std::max<milliseconds::rep>(wait.count(), 0)));
  return n > 0 ? p.revents : n;  // revents, 0 on timeout, -1 on error
}

// Numeric "address" and port of a socket's peer or own end, as httplib formats them.
bool addressOf(int fd, bool peer, std::string& address, int& port) {
  sockaddr_storage addr{};
  socklen_t len = sizeof(addr);
  int rc = peer ? ::getpeername(fd, reinterpret_cast<sockaddr*>(&addr), &len)
                : ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  if (rc != 0) return false;
  char host[NI_MAXHOST];
  char serv[NI_MAXSERV];
  if (::getnameinfo(reinterpret_cast<sockaddr*>(&addr), len, host, sizeof(host), serv, sizeof(serv),
                    NI_NUMERICHOST | NI_NUMERICSERV) != 0)
    return false;
  address = host;
  port = std::atoi(serv);
  return true;
}

// httplib's SocketStream, plus a deadline on reads: the request (headers, then body) must
// arrive by `deadline_` however the client paces it. Reads already buffered by the kernel are
// still taken after the deadline, so a complete request that merely waited in the queue is
// served; only waiting for more is refused.
class DeadlineStream final : public httplib::Stream {
 public:
  DeadlineStream(int fd, std::string address, int port, const std::atomic<socket_t>& listener, milliseconds readTimeout,
                 milliseconds writeTimeout)
      : fd_(fd),
        address_(std::move(address)),
        port_(port),
        listener_(listener),
        readTimeout_(readTimeout),
        writeTimeout_(writeTimeout) {}

  // The next request's line and headers are due by `deadline`.
  void expectRequest(Clock::time_point deadline, milliseconds allowance) {
    deadline_ = deadline;
    allowance_ = allowance;
    inBody_ = false;
  }
  // Headers are in (httplib's setup_request hook): the body gets its own allowance from now.
  void expectBody() {
    deadline_ = Clock::now() + allowance_;
    inBody_ = true;
  }

  // Keep-alive: true when a request starts arriving before `idleUntil` (and the deadline).
  bool waitForRequest(Clock::time_point idleUntil) {
    return off_ < len_ || waitReadable(std::min(idleUntil, deadline_), /*logCut=*/false);
  }
  // A read failed or met the end: httplib may still answer (400 for a body cut short), but
  // what follows on this connection is no longer a request boundary.
  bool broken() const { return broken_; }

  bool is_readable() const override {
    return off_ < len_ || pollOne(fd_, POLLIN, std::min(readTimeout_, untilDeadline())) > 0;
  }
  bool is_writable() const override {
    // As httplib's: writable in time, and the peer has not closed (a stream handler polls this
    // through DataSink::is_writable to notice a watcher that left).
    if (pollOne(fd_, POLLOUT, writeTimeout_) <= 0) return false;
    if (pollOne(fd_, POLLIN, milliseconds(0)) == 0) return true;
    char c;
    return ::recv(fd_, &c, 1, MSG_PEEK | MSG_DONTWAIT) > 0;
  }

  ssize_t read(char* ptr, size_t size) override {
    if (off_ < len_) {
      size_t n = std::min(size, len_ - off_);
      std::memcpy(ptr, buf_ + off_, n);
      off_ += n;
      return static_cast<ssize_t>(n);
    }
    if (!waitReadable(std::min(Clock::now() + readTimeout_, deadline_), /*logCut=*/true)) {
      broken_ = true;
      return -1;
    }
    // Small reads (httplib reads header lines a byte at a time) go through the buffer.
    const bool direct = size >= sizeof(buf_);
    ssize_t n = recvSome(direct ? ptr : buf_, direct ? size : sizeof(buf_));
    if (n <= 0) {
      broken_ = true;
      return n;
    }
    // A body earns time as it arrives: a large upload at a decent rate is never cut.
    if (inBody_) deadline_ += std::chrono::microseconds(static_cast<long long>(n) * 1'000'000 / kBodyMinBytesPerSecond);
    if (direct) return n;
    off_ = 0;
    len_ = static_cast<size_t>(n);
    return read(ptr, size);
  }

  ssize_t write(const char* ptr, size_t size) override {
    if (pollOne(fd_, POLLOUT, writeTimeout_) <= 0) return -1;
    ssize_t n;
    do n = ::send(fd_, ptr, size, MSG_NOSIGNAL);
    while (n < 0 && errno == EINTR);
    return n;
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    ip = address_;
    port = port_;
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override { addressOf(fd_, false, ip, port); }
  socket_t socket() const override { return fd_; }

 private:
  milliseconds untilDeadline() const {
    return std::max(milliseconds(0), std::chrono::duration_cast<milliseconds>(deadline_ - Clock::now()));
  }

  // Data (or EOF, or an error) before `until`; false on timeout or when the server stops.
  bool waitReadable(Clock::time_point until, bool logCut) {
    for (;;) {
      const auto left = std::chrono::duration_cast<milliseconds>(until - Clock::now());
      int r = pollOne(fd_, POLLIN, std::min(left, kWaitSlice));
      if (r > 0) return true;
      if (r < 0 && errno != EINTR) return false;
      if (listener_ == INVALID_SOCKET) return false;
      if (Clock::now() >= until) {
        if (logCut && Clock::now() >= deadline_)
          std::fprintf(stderr, "connection %s:%d: %s not received within the read deadline; closed\n", address_.c_str(),
                       port_, inBody_ ? "request body" : "request headers");
        return false;
      }
    }
  }

  ssize_t recvSome(char* dst, size_t size) {
    ssize_t n;
    do n = ::recv(fd_, dst, size, 0);
    while (n < 0 && errno == EINTR);
    return n;
  }

  const int fd_;
  const std::string address_;
  const int port_;
  const std::atomic<socket_t>& listener_;  // httplib sets it INVALID_SOCKET on stop()
  const milliseconds readTimeout_, writeTimeout_;
  Clock::time_point deadline_ = Clock::now();
  milliseconds allowance_{0};
  bool inBody_ = false;
  bool broken_ = false;
  char buf_[4096];
  size_t off_ = 0, len_ = 0;
};

// A complete response as bytes, for the refusal path that has no httplib stream to write it.
std::string serialize(const httplib::Response& res, const char* reason) {
  std::string body = res.body;
  if (res.content_provider_) {
    httplib::DataSink sink;
    sink.write = [&](const char* d, size_t n) {
      body.append(d, n);
      return true;
    };
    sink.is_writable = [] { return true; };
    sink.done = [] {};
    while (body.size() < res.content_length_)
      if (!res.content_provider_(body.size(), res.content_length_ - body.size(), sink)) break;
  }
  std::string out = "HTTP/1.1 " + std::to_string(res.status) + " " + reason + "\r\n";
  for (const auto& [name, value] : res.headers) out += name + ": " + value + "\r\n";
  out += "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body;
  return out;
}

}  // namespace

bool ConnectionRegistry::add(const std::string& address, int port, int fd) {
  std::lock_guard lock(mutex_);
  int& open = perAddress_[address];
  if (open >= maxPerAddress_) return false;
  ++open;
  fds_[{address, port}] = fd;
  return true;
}

void ConnectionRegistry::remove(const std::string& address, int port) {
  std::lock_guard lock(mutex_);
  if (fds_.erase({address, port}) == 0) return;
  auto it = perAddress_.find(address);
  if (it != perAddress_.end() && --it->second <= 0) perAddress_.erase(it);
}

bool ConnectionRegistry::peerClosed(const std::string& address, int port) const {
  std::lock_guard lock(mutex_);  // the fd stays open while it is registered
  auto it = fds_.find({address, port});
  if (it == fds_.end()) return false;
  // POLLRDHUP: the peer's FIN even behind unread data; POLLHUP/POLLERR: reset or gone.
  int r = pollOne(it->second, POLLRDHUP, milliseconds(0));
  return r > 0 && (r & (POLLRDHUP | POLLHUP | POLLERR));
}

int ConnectionRegistry::openFrom(const std::string& address) const {
  std::lock_guard lock(mutex_);
  auto it = perAddress_.find(address);
  return it == perAddress_.end() ? 0 : it->second;
}

LingeringCloser::LingeringCloser() : thread_([this] { run(); }) {}

LingeringCloser::~LingeringCloser() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
  for (auto& [fd, until] : fds_) ::close(fd);
}

void LingeringCloser::add(int fd) {
  std::lock_guard lock(mutex_);
  if (fds_.size() >= kMaxLingering) {
    ::close(fd);
    return;
  }
  fds_.emplace_back(fd, Clock::now() + kRefusalGrace);
  wake_.notify_all();
}

void LingeringCloser::run() {
  std::vector<pollfd> polled;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || !fds_.empty(); });
      if (stop_) return;
      polled.clear();
      for (auto& [fd, until] : fds_) polled.push_back({fd, POLLIN, 0});
    }
    // An fd is closed only here, so the copies stay valid while polled without the lock.
    ::poll(polled.data(), polled.size(), static_cast<int>(kWaitSlice.count()));
    std::lock_guard lock(mutex_);
    const Clock::time_point now = Clock::now();
    for (const pollfd& p : polled) {
      bool done = false;
      if (p.revents) {
        char drop[4096];
        ssize_t n = ::recv(p.fd, drop, sizeof(drop), MSG_DONTWAIT);
        done = n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR);
      }
      auto it = std::find_if(fds_.begin(), fds_.end(), [&](const auto& e) { return e.first == p.fd; });
      if (done || now >= it->second) {
        ::close(p.fd);
        fds_.erase(it);
      }
    }
  }
}

GuardedServer::GuardedServer(const ConnectionLimits& limits) : limits_(limits), registry_(limits.maxPerAddress) {
  size_t threads = limits.threads;
  new_task_queue = [threads] { return new StampingQueue(threads); };
}

bool GuardedServer::widenBacklog(int backlog) {
  // listen() again on a listening socket only changes its backlog (Linux).
  return svr_sock_ != INVALID_SOCKET && ::listen(svr_sock_, backlog) == 0;
}

void closeAfterThisResponse() { tCloseAfterResponse = true; }

bool GuardedServer::process_and_close_socket(socket_t sock) {
  const Clock::time_point acceptedAt = tAcceptedAt == Clock::time_point{} ? Clock::now() : tAcceptedAt;
  tAcceptedAt = {};
  std::string address;
  int port = 0;
  if (!addressOf(sock, true, address, port)) {  // the client already reset it
    ::close(sock);
    return false;
  }
  if (!registry_.add(address, port, sock)) {
    refuse(sock, address);
    return false;
  }
  bool ret = false;
  bool unreadBody = false;
  {
    auto ms = [](time_t sec, time_t usec) { return milliseconds(sec * 1000 + usec / 1000); };
    DeadlineStream strm(sock, address, port, svr_sock_, ms(read_timeout_sec_, read_timeout_usec_),
                        ms(write_timeout_sec_, write_timeout_usec_));
    Clock::time_point deadline = acceptedAt + limits_.requestReadTimeout;
    // httplib's keep-alive loop (detail::process_server_socket), with deadlines.
    for (size_t left = keep_alive_max_count_; left > 0 && svr_sock_ != INVALID_SOCKET; --left) {
      strm.expectRequest(deadline, limits_.requestReadTimeout);
      if (!strm.waitForRequest(Clock::now() + std::chrono::seconds(keep_alive_timeout_sec_))) break;
      bool closed = false;
      tCloseAfterResponse = false;
      ret = process_request(strm, left == 1, closed, [&strm](httplib::Request&) { strm.expectBody(); });
      // A request answered before its body was read: what follows on the socket is that body,
      // which must never be read as a request of its own.
      unreadBody = std::exchange(tCloseAfterResponse, false);
      if (!ret || closed || strm.broken() || unreadBody) break;
      deadline = Clock::now() + limits_.requestReadTimeout;
    }
    registry_.remove(address, port);
  }
  if (unreadBody) {
    // Dropped, not reset: the client still reads the answer it was sent.
    ::shutdown(sock, SHUT_WR);
    closer_.add(sock);
    return ret;
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  return ret;
}

void GuardedServer::refuse(socket_t sock, const std::string& address) {
  std::fprintf(stderr, "connection from %s refused: %d connections from that address already open\n", address.c_str(),
               registry_.maxPerAddress());
  httplib::Response res;
  sendError(res, ErrorCode::TooManyConnections,
            "this address already has " + std::to_string(registry_.maxPerAddress()) +
                " connections open (--max-connections-per-address); close some and retry");
  res.set_header("Connection", "close");
  res.set_header("Retry-After", "1");
  if (limits_.onRefused) limits_.onRefused("too_many_connections");
  const std::string wire = serialize(res, "Service Unavailable");
  // A fresh socket's send buffer takes the small answer whole; a client that cannot take it
  // is not worth a wait.
  (void)::send(sock, wire.data(), wire.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  ::shutdown(sock, SHUT_WR);
  closer_.add(sock);
}

}  // namespace brdfa::server
