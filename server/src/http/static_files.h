// The static UI's files, read once per version and kept in memory with a gzip copy.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

namespace brdfa::server {

struct StaticFile {
  std::shared_ptr<const std::string> bytes;
  std::shared_ptr<const std::string> gzip;  // null when the type does not compress or it would not shrink
  std::string contentType;
  std::string etag;  // quoted; changes whenever the file's size or modification time does
};

class StaticFiles {
 public:
  // The file at `path` (already resolved under the web root by the caller), re-read when its
  // size or modification time changed since the last call; nullopt when it cannot be read.
  // Text types (HTML, CSS, JavaScript, JSON, SVG) get a gzip copy, made once per version: the
  // UI's editor bundle shrinks to a fraction of its size. Thread-safe.
  std::optional<StaticFile> get(const std::filesystem::path& path);

 private:
  struct Entry {
    StaticFile file;
    std::filesystem::file_time_type mtime;
    uintmax_t size = 0;
  };
  std::mutex mutex_;
  std::map<std::filesystem::path, Entry> entries_;
};

// Content-Type for a file name's extension ("application/octet-stream" when unknown).
const char* contentTypeFor(const std::filesystem::path& path);

// True when an Accept-Encoding header value accepts gzip (a "gzip" or "*" token without q=0).
bool acceptsGzip(const std::string& acceptEncoding);

// True when an If-None-Match header value lists `etag` or is "*".
bool etagMatches(const std::string& ifNoneMatch, const std::string& etag);

}  // namespace brdfa::server
