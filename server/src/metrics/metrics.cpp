#include "metrics/metrics.h"

namespace brdfa::server {

void ServiceMetrics::countResponse(int status, std::string_view errorName) {
  std::lock_guard lock(mutex_);
  ++responses_[status];
  if (status < 400) return;
  // A handler's error always has a name (http_errors.h); anything else is named by its status.
  std::string reason = errorName.empty() ? "http_" + std::to_string(status) : std::string(errorName);
  ++rejections_[reason];
}

std::map<int, uint64_t> ServiceMetrics::responsesByStatus() const {
  std::lock_guard lock(mutex_);
  return responses_;
}

std::map<std::string, uint64_t> ServiceMetrics::rejectionsByReason() const {
  std::lock_guard lock(mutex_);
  return {rejections_.begin(), rejections_.end()};
}

}  // namespace brdfa::server
