#include "http/http_errors.h"

#include "http/http_body.h"

namespace brdfa::server {

const char* errorNameForStatus(int status) {
  switch (status) {
    case 400: return "bad_request";
    case 404: return "not_found";
    case 405: return "method_not_allowed";
    case 409: return "conflict";
    case 413: return "payload_too_large";
    case 414: return "uri_too_long";
    case 416: return "range_not_satisfiable";
    case 422: return "compile_error";
    case 429: return "too_many_sessions";
    case 503: return "unavailable";
    default: return status >= 500 ? "internal" : "bad_request";
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
  const char* name = errorCodeName(ErrorCode::QuotaExceeded);
  res.set_header(kErrorNameHeader, name);
  sendJson(res, {{"error", name}, {"quota", quota}, {"limit", limit}, {"used", used}, {"message", message}},
           errorHttpStatus(ErrorCode::QuotaExceeded));
}

void sendJson(httplib::Response& res, const nlohmann::json& body, int status) {
  res.status = status;
  // `replace` keeps invalid UTF-8 from user text (a .brdf file, a name) from throwing here.
  sendBody(res, body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
}

namespace {

// The error body every failure gets, under `status`.
void sendErrorBody(httplib::Response& res, int status, const char* name, const std::string& message,
                   const std::string& field) {
  nlohmann::json body{{"error", name}, {"message", message}};
  if (!field.empty()) body["field"] = field;
  res.set_header(kErrorNameHeader, name);
  sendJson(res, body, status);
}

}  // namespace

void sendError(httplib::Response& res, const Error& error) {
  const char* name = errorCodeName(error.code);
  nlohmann::json body{{"error", name}, {"message", error.message}};
  if (!error.field.empty()) body["field"] = error.field;
  res.set_header(kErrorNameHeader, name);
  if (error.code == ErrorCode::CompileError || !error.diagnostics.empty())
    body["diagnostics"] = diagnosticsToJson(error.diagnostics);
  sendJson(res, body, errorHttpStatus(error.code));
}

void sendError(httplib::Response& res, ErrorCode code, std::string message, std::string field) {
  sendErrorBody(res, errorHttpStatus(code), errorCodeName(code), message, field);
}

void sendStatusError(httplib::Response& res, const std::string& message) {
  sendErrorBody(res, res.status, errorNameForStatus(res.status), message, {});
}

}  // namespace brdfa::server
