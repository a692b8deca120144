// Response bodies that go out exactly as given.
#pragma once

#include <httplib.h>

#include <memory>
#include <string>

namespace brdfa::server {

// Sets `body` as the response, sent as is with Content-Length. Debian's cpp-httplib 0.11 is
// built with brotli and compresses every text/* and application/json body itself when the
// client accepts br, at brotli's default quality 11, which costs far more CPU
// than the answer itself, on every request. A sized content provider is never compressed by httplib, so
// every body the service sends goes through here (static files come compressed once, cached).
void sendBody(httplib::Response& res, std::string body, const std::string& contentType);

// The same for a body shared with a cache: no copy per request.
void sendBody(httplib::Response& res, std::shared_ptr<const std::string> body, const std::string& contentType);

}  // namespace brdfa::server
