#include "app/http_server.h"

#include <httplib.h>
#include <netinet/tcp.h>

#include "api/routes.h"
#include "http/connection_guard.h"
#include "http/request_body.h"
#include "service/service.h"

namespace brdfa::server {

HttpServer::~HttpServer() {
  stop();
  // The worker threads are gone once run() returned; the listener before the service.
  http_.reset();
  service_.reset();
}

Result<std::unique_ptr<HttpServer>> HttpServer::create(const ServerConfig& config, std::vector<std::string>& log) {
  Result<std::unique_ptr<Service>> service = Service::create(config, log);
  if (!service) return service.takeError();
  std::unique_ptr<HttpServer> out(new HttpServer());
  out->config_ = config;
  out->service_ = std::move(service.value());
  // Every stream client holds one worker for as long as it watches; slow or greedy clients
  // hold one for no longer than the read deadline (connection_guard.h).
  ConnectionLimits limits;
  limits.threads = static_cast<size_t>(config.threads);
  limits.maxPerAddress = config.maxConnectionsPerAddress;
  limits.requestReadTimeout = std::chrono::seconds(config.requestReadTimeoutSec);
  ServiceMetrics* metrics = &out->service_->metrics;
  limits.onRefused = [metrics](const char* reason) { metrics->countResponse(503, reason); };
  if (config.maxConnectionsPerAddress >= config.threads)
    log.push_back("warning: --max-connections-per-address " + std::to_string(config.maxConnectionsPerAddress) +
                  " is not below --threads " + std::to_string(config.threads) +
                  ": one client address can hold every worker until the read deadline");
  out->http_ = std::make_unique<GuardedServer>(limits);
  out->service_->connections = &out->http_->connections();
  httplib::Server& http = *out->http_;
  // cpp-httplib's default sets SO_REUSEPORT, with which a second server binds a port already
  // served and the kernel spreads connections over both: a user starting the service twice
  // got half the requests answered by each (a BRDF PUT to one, 404 from the other).
  // SO_REUSEADDR alone still rebinds a port left in TIME_WAIT and refuses one in use.
  http.set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
    // Inherited by accepted sockets: a response's header and body writes go out at once,
    // instead of the body waiting for the client's delayed ACK of the header on every request.
    ::setsockopt(sock, IPPROTO_TCP, TCP_NODELAY, &yes, sizeof(yes));
  });

  // Uploads need more than a JSON body; the JSON and .brdf routes check their own, smaller
  // limits (readJsonBody, readBrdfTextBody), the upload route its file limit.
  http.set_payload_max_length(out->service_->maxRequestBody());
  // Short keep-alive: idle browser connections otherwise hold shutdown for the full timeout.
  http.set_keep_alive_timeout(2);

  Service& s = *out->service_;
  registerAccessGate(http, s);
  registerSystemRoutes(http, s);
  registerAuthRoutes(http, s);
  registerBrdfRoutes(http, s);
  registerSessionRoutes(http, s);
  registerRenderRoutes(http, s);
  registerAnalysisRoutes(http, s);
  registerDifferenceRoutes(http, s);
  registerJobRoutes(http, s);
  registerAssetRoutes(http, s);
  registerStaticRoutes(http, s);
  return out;
}

void HttpServer::beginDrain() { service_->draining = true; }

bool HttpServer::drained() const {
  return service_->activeStreams.load() == 0 && service_->frameWaiters.load() == 0 &&
         service_->renderSlots.taken() == 0;
}

Result<int> HttpServer::bind() {
  int port = config_.port;
  if (port == 0) {
    port = http_->bind_to_any_port(config_.host);
    if (port <= 0) return makeError(ErrorCode::InvalidArgument, "cannot bind " + config_.host + " on any port");
  } else if (!http_->bind_to_port(config_.host, port)) {
    return makeError(ErrorCode::InvalidArgument, "cannot bind " + config_.host + ":" + std::to_string(port));
  }
  http_->widenBacklog(SOMAXCONN);
  return port;
}

bool HttpServer::run() { return http_->listen_after_bind(); }

void HttpServer::stop() {
  if (service_) service_->beginShutdown();
  if (http_) http_->stop();
}

}  // namespace brdfa::server
