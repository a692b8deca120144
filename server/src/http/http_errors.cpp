#include "http/http_errors.h"

#include "http/http_body.h"

namespace brdfa::server {

int httpStatusFor(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidArgument:
      return 400;
    case ErrorCode::NotFound:
      return 404;
    case ErrorCode::CompileError:
      return 422;
    // A valid request this build or device cannot do is still the client's to change.
    case ErrorCode::Unsupported:
      return 400;
    // The device is a shared resource that may come back (or the server gets restarted).
    case ErrorCode::DeviceError:
      return 503;
    case ErrorCode::OverBudget:
      return 507;
    // The program itself is what a watchdog stopped: the client's to change.
    case ErrorCode::RenderBudget:
      return 422;
    case ErrorCode::Internal:
      return 500;
  }
  return 500;
}

const char* errorName(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidArgument:
      return "invalid_argument";
    case ErrorCode::NotFound:
      return "not_found";
    case ErrorCode::CompileError:
      return "compile_error";
    case ErrorCode::Unsupported:
      return "unsupported";
    case ErrorCode::DeviceError:
      return "device_error";
    case ErrorCode::OverBudget:
      return "memory_budget";
    case ErrorCode::RenderBudget:
      return "render_budget";
    case ErrorCode::Internal:
      return "internal";
  }
  return "internal";
}

const char* errorNameForStatus(int status) {
  switch (status) {
    case 400:
      return "bad_request";
    case 404:
      return "not_found";
    case 405:
      return "method_not_allowed";
    case 409:
      return "conflict";
    case 413:
      return "payload_too_large";
    case 414:
      return "uri_too_long";
    case 416:
      return "range_not_satisfiable";
    case 422:
      return "compile_error";
    case 429:
      return "too_many_sessions";
    case 503:
      return "unavailable";
    default:
      return status >= 500 ? "internal" : "bad_request";
  }
}

nlohmann::json diagnosticToJson(const Diagnostic& d) {
  return nlohmann::json{{"line", d.line}, {"column", d.column}, {"severity", d.severity}, {"message", d.message}};
}

nlohmann::json diagnosticsToJson(const std::vector<Diagnostic>& ds) {
  nlohmann::json out = nlohmann::json::array();
  for (const Diagnostic& d : ds) out.push_back(diagnosticToJson(d));
  return out;
}

void sendQuotaExceeded(httplib::Response& res, const std::string& quota, uint64_t limit, uint64_t used,
                       const std::string& message) {
  res.set_header(kErrorNameHeader, "quota_exceeded");
  sendJson(res, {{"error", "quota_exceeded"}, {"quota", quota}, {"limit", limit}, {"used", used}, {"message", message}},
           429);
}

void sendJson(httplib::Response& res, const nlohmann::json& body, int status) {
  res.status = status;
  // `replace` keeps invalid UTF-8 from user text (a .brdf file, a name) from throwing here.
  sendBody(res, body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
}

void sendError(httplib::Response& res, int status, const std::string& code, const std::string& message,
               const std::string& field) {
  nlohmann::json body{{"error", code}, {"message", message}};
  if (!field.empty()) body["field"] = field;
  res.set_header(kErrorNameHeader, code);
  sendJson(res, body, status);
}

void sendError(httplib::Response& res, const Error& error) {
  nlohmann::json body{{"error", errorName(error.code)}, {"message", error.message}};
  if (!error.field.empty()) body["field"] = error.field;
  res.set_header(kErrorNameHeader, errorName(error.code));
  if (error.code == ErrorCode::CompileError || !error.diagnostics.empty())
    body["diagnostics"] = diagnosticsToJson(error.diagnostics);
  sendJson(res, body, httpStatusFor(error.code));
}

}  // namespace brdfa::server
