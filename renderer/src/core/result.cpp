#include "brdfa/result.h"

#include <iterator>

namespace brdfa {

namespace {

// The one table of error codes: the stable snake_case name (in JSON error bodies and logs)
// and the HTTP status of each (docs/api.md, Errors).
struct ErrorCodeInfo {
  ErrorCode code;
  const char* name;
  int httpStatus;
};

constexpr ErrorCodeInfo kErrorCodes[] = {
    {ErrorCode::InvalidArgument, "invalid_argument", 400},
    {ErrorCode::NotFound, "not_found", 404},
    {ErrorCode::CompileError, "compile_error", 422},
    // A valid request this build or device cannot do is still the client's to change.
    {ErrorCode::Unsupported, "unsupported", 400},
    // The device is a shared resource that may come back (or the server gets restarted).
    {ErrorCode::DeviceError, "device_error", 503},
    {ErrorCode::OverBudget, "memory_budget", 507},
    // The program itself is what a watchdog stopped: the client's to change.
    {ErrorCode::RenderBudget, "render_budget", 422},
    {ErrorCode::Internal, "internal", 500},
    {ErrorCode::BadJson, "bad_json", 400},
    {ErrorCode::Unauthorized, "unauthorized", 401},
    {ErrorCode::Forbidden, "forbidden", 403},
    {ErrorCode::Conflict, "conflict", 409},
    {ErrorCode::NoScene, "no_scene", 409},
    {ErrorCode::PayloadTooLarge, "payload_too_large", 413},
    {ErrorCode::TooManySessions, "too_many_sessions", 429},
    {ErrorCode::TooManyJobs, "too_many_jobs", 429},
    {ErrorCode::QuotaExceeded, "quota_exceeded", 429},
    // nginx's status for a client that closed the connection; nobody reads the answer.
    {ErrorCode::ClientClosed, "client_closed", 499},
    {ErrorCode::StorageError, "storage_error", 500},
    {ErrorCode::StorageFull, "storage_full", 507},
    {ErrorCode::Busy, "busy", 503},
    {ErrorCode::Unavailable, "unavailable", 503},
    {ErrorCode::TooManyStreams, "too_many_streams", 503},
    {ErrorCode::TooManyConnections, "too_many_connections", 503},
    {ErrorCode::Draining, "draining", 503},
    {ErrorCode::CrossSite, "cross_site", 403},
};

const ErrorCodeInfo& infoFor(ErrorCode code) {
  for (const ErrorCodeInfo& info : kErrorCodes)
    if (info.code == code) return info;
  return kErrorCodes[static_cast<size_t>(ErrorCode::Internal)];
}

}  // namespace

static_assert(std::size(kErrorCodes) == static_cast<size_t>(ErrorCode::CrossSite) + 1, "one row per ErrorCode");

const char* errorCodeName(ErrorCode code) { return infoFor(code).name; }

int errorHttpStatus(ErrorCode code) { return infoFor(code).httpStatus; }

}  // namespace brdfa
