// The HTTP front: a cpp-httplib server with the routes over one Service.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "brdfa/result.h"
#include "config/config.h"

namespace httplib {
class Server;
}

namespace brdfa::server {

struct Service;
class GuardedServer;

class HttpServer {
 public:
  // Opens the device and sets up routes; binds nothing yet. `log` gets start-up warnings.
  static Result<std::unique_ptr<HttpServer>> create(const ServerConfig& config, std::vector<std::string>& log);
  ~HttpServer();

  // Binds config.host:config.port (port 0: any free port). Returns the bound port, or an error.
  Result<int> bind();

  // Serves until stop(). Returns false when the listener failed.
  bool run();

  // Safe from any thread, more than once: wakes streams and waiters, stops sessions, closes the
  // listener. run() returns once the worker threads have finished.
  void stop();

  // Draining (SIGTERM with --drain-seconds): from beginDrain() on, new sessions and jobs get
  // 503 `draining` and /api/ready 503; everything else is still served. drained() is true once
  // no stream, frame wait or one-shot render is open, when stop() loses nobody's answer.
  void beginDrain();
  bool drained() const;

 private:
  HttpServer() = default;
  std::unique_ptr<Service> service_;
  std::unique_ptr<GuardedServer> http_;  // httplib::Server with connection limits
  ServerConfig config_;
};

}  // namespace brdfa::server
