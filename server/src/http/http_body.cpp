#include "http/http_body.h"

#include <algorithm>

namespace brdfa::server {

void sendBody(httplib::Response& res, std::shared_ptr<const std::string> body, const std::string& contentType) {
  const size_t size = body->size();
  if (size == 0) {  // a sized provider needs bytes to send; an empty body has nothing to compress
    res.set_content(std::string(), contentType.c_str());
    return;
  }
  res.set_content_provider(size, contentType.c_str(),
                           [body = std::move(body)](size_t offset, size_t length, httplib::DataSink& sink) {
                             length = std::min(length, body->size() - std::min(offset, body->size()));
                             return sink.write(body->data() + offset, length);
                           });
}

void sendBody(httplib::Response& res, std::string body, const std::string& contentType) {
  sendBody(res, std::make_shared<const std::string>(std::move(body)), contentType);
}

}  // namespace brdfa::server
