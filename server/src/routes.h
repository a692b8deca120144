// Route registration, one file per resource. Handlers only parse and validate the request,
// call the Service, and answer through http_errors (the one place errors become HTTP).
#pragma once

#include <httplib.h>

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "brdfa_server/service.h"

namespace brdfa::server {

void registerSystemRoutes(httplib::Server& server, Service& service);  // health, handlers
void registerBrdfRoutes(httplib::Server& server, Service& service);
void registerSessionRoutes(httplib::Server& server, Service& service);
void registerRenderRoutes(httplib::Server& server, Service& service);
void registerJobRoutes(httplib::Server& server, Service& service);  // batch tests
void registerStaticRoutes(httplib::Server& server, Service& service);  // last: catch-all GET

// Parses the body as JSON; on failure answers 400 bad_json and returns nullopt.
std::optional<nlohmann::json> readJsonBody(const httplib::Request& req, httplib::Response& res);

// The body as .brdf text; on failure (over kMaxBrdfSource, empty) answers and returns nullopt.
std::optional<std::string> readBrdfTextBody(const httplib::Request& req, httplib::Response& res);

// Headers every image response carries.
void setFrameHeaders(httplib::Response& res, const FrameStats& stats);

}  // namespace brdfa::server
