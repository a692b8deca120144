// The one place where failures become HTTP responses (docs/design.md section 7): every error body is
// {"error": "<code>", "message": "...", "field": "..." (when known), "diagnostics": [...]
// (compile errors)}.
#pragma once

#include <httplib.h>

#include <nlohmann/json.hpp>
#include <string>

#include "brdfa/result.h"

namespace brdfa::server {

nlohmann::json diagnosticToJson(const Diagnostic& d);
nlohmann::json diagnosticsToJson(const std::vector<Diagnostic>& ds);

// Both sendError overloads also put the error's name in this header, for /metrics' rejections
// by reason; the post-routing handler (api/system.cpp) takes it off before the response goes.
inline constexpr const char* kErrorNameHeader = "X-Brdfa-Error-Name";

// Writes `error` as the JSON body, with the status and "error" name of its code (errorHttpStatus
// and errorCodeName in brdfa/result.h: the one table of codes).
void sendError(httplib::Response& res, const Error& error);
// The same for an error made here: sendError(res, ErrorCode::NotFound, "no session 'x'", "session").
void sendError(httplib::Response& res, ErrorCode code, std::string message, std::string field = {});

// For a response httplib made by itself (its res.status: an unknown route, 405, 413, 414, ...):
// the JSON error body, named by errorNameForStatus.
void sendStatusError(httplib::Response& res, const std::string& message);

// 429 quota_exceeded: one person is past one of their quotas (config.h's Quotas); `message`
// says how to free room. {"error", "quota", "limit", "used", "message"}.
void sendQuotaExceeded(httplib::Response& res, const std::string& quota, uint64_t limit, uint64_t used,
                       const std::string& message);

void sendJson(httplib::Response& res, const nlohmann::json& body, int status = 200);

// Default "error" name for a bare HTTP status (for responses that httplib produced itself, e.g.
// 413 or 404 for unknown routes).
const char* errorNameForStatus(int status);

}  // namespace brdfa::server
