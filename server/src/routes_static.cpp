// The static UI from <root>/web/. Registered last: it answers every GET no API route took.
#include <filesystem>
#include <fstream>
#include <sstream>

#include "brdfa_server/http_errors.h"
#include "routes.h"

namespace brdfa::server {

namespace {

const char* contentTypeFor(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  // ES modules are only executed when served with a JavaScript MIME type.
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json" || ext == ".map") return "application/json";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".ico") return "image/x-icon";
  if (ext == ".wasm") return "application/wasm";
  if (ext == ".txt" || ext == ".brdf") return "text/plain; charset=utf-8";
  return "application/octet-stream";
}

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
      return sendError(res, 404, "not_found", "no such resource: GET " + req.path);
    if (rel.empty() || rel.back() == '/') rel += "index.html";
    auto path = resolveUnder(std::filesystem::path(service.config.root) / "web", rel);
    if (!path) return sendError(res, 400, "invalid_argument", "path not allowed: " + req.path, "path");
    std::error_code ec;
    if (!std::filesystem::is_regular_file(*path, ec))
      return sendError(res, 404, "not_found", "no such file: " + req.path);
    std::ifstream in(*path, std::ios::binary);
    std::ostringstream data;
    data << in.rdbuf();
    if (!in) return sendError(res, 500, "internal", "cannot read " + req.path);
    res.set_header("Cache-Control", "no-cache");
    res.set_content(data.str(), contentTypeFor(*path));
  });
}

}  // namespace brdfa::server
