// The one place where failures become HTTP responses (docs/design.md section 4): every error body is
// {"error": "<code>", "message": "...", "field": "..." (when known), "diagnostics": [...]
// (compile errors)}.
#pragma once

#include <httplib.h>

#include <nlohmann/json.hpp>
#include <string>

#include "brdfa/result.h"

namespace brdfa::server {

// HTTP status for a renderer/server error code.
int httpStatusFor(ErrorCode code);

// Snake-case name used as "error" in bodies ("invalid_argument", "compile_error", ...).
const char* errorName(ErrorCode code);

nlohmann::json diagnosticToJson(const Diagnostic& d);
nlohmann::json diagnosticsToJson(const std::vector<Diagnostic>& ds);

// Both sendError overloads also put the error's name in this header, for /metrics' rejections
// by reason; the post-routing handler (routes_system.cpp) takes it off before the response goes.
inline constexpr const char* kErrorNameHeader = "X-Brdfa-Error-Name";

// Writes `error` as the JSON body with its mapped status.
void sendError(httplib::Response& res, const Error& error);

// Writes an error that has no brdfa::ErrorCode (bad_json, conflict, payload_too_large, ...).
void sendError(httplib::Response& res, int status, const std::string& code, const std::string& message,
               const std::string& field = {});

// 429 quota_exceeded: one person is past one of their quotas (config.h's Quotas); `message`
// says how to free room. {"error", "quota", "limit", "used", "message"}.
void sendQuotaExceeded(httplib::Response& res, const std::string& quota, uint64_t limit, uint64_t used,
                       const std::string& message);

void sendJson(httplib::Response& res, const nlohmann::json& body, int status = 200);

// Default "error" code for a bare HTTP status (used by the error handler for responses that
// httplib produced itself, e.g. 413 or 404 for unknown routes).
const char* errorNameForStatus(int status);

}  // namespace brdfa::server
