#include "http/static_files.h"

#include <zlib.h>

#include <cstdio>
#include <fstream>
#include <sstream>

namespace brdfa::server {

namespace {

// gzip (RFC 1952) of `data` at zlib level 6; nullopt if zlib fails.
std::optional<std::string> gzipOf(const std::string& data) {
  z_stream zs{};
  // windowBits 15 + 16: a gzip header and trailer instead of zlib's.
  if (deflateInit2(&zs, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) return std::nullopt;
  std::string out(deflateBound(&zs, static_cast<uLong>(data.size())) + 32, '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  zs.avail_in = static_cast<uInt>(data.size());
  zs.next_out = reinterpret_cast<Bytef*>(out.data());
  zs.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&zs, Z_FINISH);
  const size_t written = zs.total_out;
  deflateEnd(&zs);
  if (rc != Z_STREAM_END) return std::nullopt;
  out.resize(written);
  return out;
}

bool compressible(const std::string& contentType) {
  return contentType.rfind("text/", 0) == 0 || contentType.rfind("application/json", 0) == 0 ||
         contentType.rfind("image/svg+xml", 0) == 0;
}

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

// Calls f(token, params) for each comma-separated element of a header value.
template <class F>
void forEachElement(const std::string& value, F&& f) {
  std::stringstream elements(value);
  for (std::string element; std::getline(elements, element, ',');) {
    const size_t semi = element.find(';');
    f(trim(element.substr(0, semi)), semi == std::string::npos ? std::string() : trim(element.substr(semi + 1)));
  }
}

}  // namespace

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

bool acceptsGzip(const std::string& acceptEncoding) {
  bool ok = false;
  forEachElement(acceptEncoding, [&](const std::string& token, const std::string& params) {
    if (token != "gzip" && token != "*") return;
    // q=0 (or 0.0, 0.00, 0.000) refuses the coding.
    const bool refused = params.rfind("q=0", 0) == 0 && params.find_first_not_of("q=0.") == std::string::npos;
    if (!refused) ok = true;
  });
  return ok;
}

bool etagMatches(const std::string& ifNoneMatch, const std::string& etag) {
  bool match = false;
  forEachElement(ifNoneMatch, [&](const std::string& token, const std::string&) {
    // A weak validator (W/"...") matches its strong form for If-None-Match (RFC 9110 13.1.2).
    const std::string strong = token.rfind("W/", 0) == 0 ? token.substr(2) : token;
    if (strong == etag || strong == "*") match = true;
  });
  return match;
}

std::optional<StaticFile> StaticFiles::get(const std::filesystem::path& path) {
  std::error_code ec;
  const auto mtime = std::filesystem::last_write_time(path, ec);
  if (ec) return std::nullopt;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return std::nullopt;
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(path);
    if (it != entries_.end() && it->second.mtime == mtime && it->second.size == size) return it->second.file;
  }
  // Read and compress outside the lock; two requests racing for a new version both do it once.
  std::ifstream in(path, std::ios::binary);
  std::ostringstream data;
  data << in.rdbuf();
  if (!in) return std::nullopt;
  Entry entry;
  entry.mtime = mtime;
  entry.size = size;
  StaticFile& f = entry.file;
  f.contentType = contentTypeFor(path);
  f.bytes = std::make_shared<const std::string>(data.str());
  if (compressible(f.contentType)) {
    std::optional<std::string> gz = gzipOf(*f.bytes);
    if (gz && gz->size() < f.bytes->size()) f.gzip = std::make_shared<const std::string>(std::move(*gz));
  }
  char tag[48];
  std::snprintf(tag, sizeof tag, "\"%jx-%llx\"", size,
                static_cast<unsigned long long>(mtime.time_since_epoch().count()));
  f.etag = tag;
  std::lock_guard lock(mutex_);
  entries_[path] = entry;
  return f;
}

}  // namespace brdfa::server
