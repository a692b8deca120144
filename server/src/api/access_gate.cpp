// Who asks, before any route runs: the cross-site check, the identity of the request, and the
// 401 for /api routes that need one (docs/api.md, Identities and ownership).
#include <cctype>
#include <string_view>

#include "api/routes.h"
#include "http/connection_guard.h"
#include "http/http_errors.h"
#include "util/auth_crypto.h"

namespace brdfa::server {

namespace {

// The identity of the request this worker thread is serving: httplib runs the pre-routing
// handler and the route on the same thread, one request at a time.
struct CurrentRequest {
  const httplib::Request* request = nullptr;
  std::optional<Identity> identity;
};
thread_local CurrentRequest tCurrent;

bool isStateChanging(const std::string& method) {
  return method == "POST" || method == "PUT" || method == "PATCH" || method == "DELETE";
}

std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// "host:port" of an authority ("example.org", "[::1]:8080"), the port defaulted by scheme.
std::string withPort(std::string authority, std::string_view scheme) {
  const size_t bracket = authority.rfind(']');
  const size_t colon = authority.rfind(':');
  const bool hasPort = colon != std::string::npos && (bracket == std::string::npos || colon > bracket);
  if (!hasPort) authority += scheme == "https" ? ":443" : ":80";
  return authority;
}

// Whether a browser sent this request from a page of another origin: its Origin names another
// host and port than the Host it was sent to (or is "null": a sandboxed or file page), or
// Sec-Fetch-Site says cross-site. Requests without either header (scripts, curl) are not.
bool fromAnotherSite(const httplib::Request& req) {
  if (lower(req.get_header_value("Sec-Fetch-Site")) == "cross-site") return true;
  if (!req.has_header("Origin")) return false;
  const std::string origin = lower(req.get_header_value("Origin"));
  const size_t sep = origin.find("://");
  if (origin == "null" || sep == std::string::npos) return true;
  const std::string scheme = origin.substr(0, sep);
  std::string authority = origin.substr(sep + 3);
  if (size_t slash = authority.find('/'); slash != std::string::npos) authority.resize(slash);
  return withPort(authority, scheme) != withPort(lower(req.get_header_value("Host")), scheme);
}

// GET .../stream or .../frame with ?key=: read with the session's view key, no token needed.
bool isViewKeyRead(const httplib::Request& req) {
  if (req.method != "GET" || !req.has_param("key")) return false;
  const std::string_view path = req.path;
  auto endsWith = [&](std::string_view tail) {
    return path.size() > tail.size() && path.substr(path.size() - tail.size()) == tail;
  };
  return path.rfind("/api/sessions/", 0) == 0 && (endsWith("/stream") || endsWith("/frame"));
}

// Routes that answer without an identity: probes, joining, and the view-key reads.
bool isPublic(const httplib::Request& req) {
  if (req.path.rfind("/api/", 0) != 0 && req.path != "/api") return true;  // the UI, /metrics
  if (req.method == "GET" && (req.path == "/api/health" || req.path == "/api/ready")) return true;
  if (req.method == "POST" && req.path == "/api/auth/join") return true;
  return isViewKeyRead(req);
}

// Refused before its body was read: the connection closes after the answer, else the unread body
// (a cross-site form can make it a whole request) would be read as the next request.
httplib::Server::HandlerResponse refuse(httplib::Response& res, ErrorCode code, const std::string& message) {
  sendError(res, code, message);
  res.set_header("Connection", "close");
  closeAfterThisResponse();
  return httplib::Server::HandlerResponse::Handled;
}

}  // namespace

void registerAccessGate(httplib::Server& server, Service& service) {
  server.set_pre_routing_handler([&service](const httplib::Request& req, httplib::Response& res) {
    tCurrent.request = &req;
    tCurrent.identity.reset();
    if (isStateChanging(req.method)) {
      // A cross-site form or fetch can change nothing, whatever it carries.
      if (fromAnotherSite(req))
        return refuse(res, ErrorCode::CrossSite, "state-changing requests from a page of another site are refused");
      // proxy mode: the front's sign-on cookie is ambient, so a request must also carry a header
      // that no cross-site form can set.
      if (service.auth->mode() == AuthMode::Proxy && !req.has_header("X-Brdfa-Client"))
        return refuse(res, ErrorCode::CrossSite,
                      "state-changing requests need the header X-Brdfa-Client (any value) behind a sign-on proxy");
    }
    tCurrent.identity = service.auth->identify(req);
    if (!tCurrent.identity && !isPublic(req)) {
      res.set_header("WWW-Authenticate", "Bearer realm=\"brdfa\"");
      return refuse(res, ErrorCode::Unauthorized,
                    service.auth->mode() == AuthMode::Proxy
                        ? "no signed-in user: sign in through the site's front"
                        : "send your token as 'Authorization: Bearer <token>' (from a join link, or from the teacher)");
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
}

const Identity& requester(const httplib::Request& req) {
  // Nobody: owns nothing (no owner is "\x01"), may read only what everyone may.
  static const Identity nobody{"\x01", "", Role::Student, ""};
  if (tCurrent.request != &req || !tCurrent.identity) return nobody;
  return *tCurrent.identity;
}

bool requesterKnown(const httplib::Request& req) { return tCurrent.request == &req && tCurrent.identity.has_value(); }

bool hasViewKey(const httplib::Request& req, const Session& session) {
  return req.has_param("key") && constantTimeEqual(req.get_param_value("key"), session.ownership().viewKey);
}

bool requireTeacher(const httplib::Request& req, httplib::Response& res) {
  if (requester(req).teacher()) return true;
  sendError(res, ErrorCode::Forbidden, "only the teacher may do this");
  return false;
}

}  // namespace brdfa::server
