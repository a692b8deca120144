// The static UI from <root>/web/. Registered last: it answers every GET no API route took.
#include <filesystem>
#include <sstream>

#include "api/routes.h"
#include "http/http_body.h"
#include "http/http_errors.h"
#include "http/static_files.h"

namespace brdfa::server {

namespace {

// Relative URL path -> file under `webRoot`, or nullopt when it is not allowed. Rejected:
// any `..` segment, backslashes, NUL, absolute paths, and (after resolving symlinks) anything
// outside the web root.
std::optional<std::filesystem::path> resolveUnder(const std::filesystem::path& webRoot, const std::string& rel) {
  namespace fs = std::filesystem;
  if (rel.find('\0') != std::string::npos || rel.find('\\') != std::string::npos || (!rel.empty() && rel[0] == '/'))
    return std::nullopt;
  std::stringstream segments(rel);
  for (std::string seg; std::getline(segments, seg, '/');)
    if (seg == "..") return std::nullopt;
  std::error_code ec;
  fs::path root = fs::weakly_canonical(webRoot, ec);
  if (ec) return std::nullopt;
  fs::path full = fs::weakly_canonical(root / rel, ec);
  if (ec) return std::nullopt;
  auto [rootEnd, fullIt] = std::mismatch(root.begin(), root.end(), full.begin(), full.end());
  if (rootEnd != root.end()) return std::nullopt;
  return full;
}

}  // namespace

void registerStaticRoutes(httplib::Server& server, Service& service) {
  server.Get("/(.*)", [&service](const httplib::Request& req, httplib::Response& res) {
    std::string rel = req.matches[1];
    if (rel == "api" || rel.rfind("api/", 0) == 0)
      return sendError(res, ErrorCode::NotFound, "no such resource: GET " + req.path);
    if (rel.empty() || rel.back() == '/') rel += "index.html";
    auto path = resolveUnder(std::filesystem::path(service.config.root) / "web", rel);
    if (!path) return sendError(res, ErrorCode::InvalidArgument, "path not allowed: " + req.path, "path");
    std::error_code ec;
    if (!std::filesystem::is_regular_file(*path, ec))
      return sendError(res, ErrorCode::NotFound, "no such file: " + req.path);
    std::optional<StaticFile> file = service.staticFiles.get(*path);
    if (!file) return sendError(res, ErrorCode::Internal, "cannot read " + req.path);
    // no-cache: the browser revalidates each time (the UI changes with every build), and the
    // ETag turns an unchanged file into a bodiless 304.
    res.set_header("Cache-Control", "no-cache");
    res.set_header("ETag", file->etag);
    res.set_header("Vary", "Accept-Encoding");
    if (etagMatches(req.get_header_value("If-None-Match"), file->etag)) {
      res.status = 304;
      return;
    }
    if (file->gzip && acceptsGzip(req.get_header_value("Accept-Encoding"))) {
      res.set_header("Content-Encoding", "gzip");
      return sendBody(res, file->gzip, file->contentType);
    }
    sendBody(res, file->bytes, file->contentType);
  });
}

}  // namespace brdfa::server
