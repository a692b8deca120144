// Route registration, one file per resource. Handlers only parse and validate the request,
// call the Service, and answer through http_errors (the one place errors become HTTP).
#pragma once

#include <httplib.h>

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "service/service.h"
#include "sessions/session.h"

namespace brdfa::server {

// A route handler with the Service it works on; withService binds one into what httplib takes.
using RouteHandler = void (*)(Service&, const httplib::Request&, httplib::Response&);
using ReadingRouteHandler = void (*)(Service&, const httplib::Request&, httplib::Response&,
                                     const httplib::ContentReader&);
inline httplib::Server::Handler withService(Service& service, RouteHandler handler) {
  return [&service, handler](const httplib::Request& req, httplib::Response& res) { handler(service, req, res); };
}
inline httplib::Server::HandlerWithContentReader withService(Service& service, ReadingRouteHandler handler) {
  return [&service, handler](const httplib::Request& req, httplib::Response& res,
                             const httplib::ContentReader& reader) { handler(service, req, res, reader); };
}

// First: the pre-routing gate (cross-site refusals, the requester's identity, 401).
void registerAccessGate(httplib::Server& server, Service& service);
void registerAuthRoutes(httplib::Server& server, Service& service);    // /api/auth/...
void registerSystemRoutes(httplib::Server& server, Service& service);  // health, handlers
void registerBrdfRoutes(httplib::Server& server, Service& service);    // registers the presets' first
void registerPresetRoutes(httplib::Server& server, Service& service);
void registerSessionRoutes(httplib::Server& server, Service& service);
void registerRenderRoutes(httplib::Server& server, Service& service);
void registerAnalysisRoutes(httplib::Server& server, Service& service);    // plots of BRDFs
void registerDifferenceRoutes(httplib::Server& server, Service& service);  // side by side: A - B
void registerJobRoutes(httplib::Server& server, Service& service);         // batch tests
void registerAssetRoutes(httplib::Server& server, Service& service);       // uploads, listing
void registerStaticRoutes(httplib::Server& server, Service& service);      // last: catch-all GET

// GET /metrics' body: the Prometheus text format (metrics_exposition.cpp).
std::string metricsText(const Service& service);

// The person the request acts for, as the gate identified it; for a request without one (a
// view-key read) a nobody who owns nothing.
const Identity& requester(const httplib::Request& req);
bool requesterKnown(const httplib::Request& req);
// Whether the request's ?key= is the session's view key (compared in constant time).
bool hasViewKey(const httplib::Request& req, const Session& session);
// True for the teacher; else answers 403 forbidden.
bool requireTeacher(const httplib::Request& req, httplib::Response& res);

// True, having answered 503 `draining`, when the server drains (SIGTERM): it takes no new
// sessions or jobs, and the balancer sends them to another replica.
bool refuseWhileDraining(const Service& service, httplib::Response& res);

// Parses the body as JSON; on failure answers 400 bad_json and returns nullopt.
std::optional<nlohmann::json> readJsonBody(const httplib::Request& req, httplib::Response& res);

// The body as .brdf text, whatever its content type (a multipart form: its only part), read
// through a content-reader route; on failure (over kMaxBrdfSource, empty, unreadable) answers
// and returns nullopt.
std::optional<std::string> readBrdfTextBody(const httplib::Request& req, httplib::Response& res,
                                            const httplib::ContentReader& reader);

// What a route does with the session it names: reads it (its owner, the teacher, everyone for
// `default`, a view-key holder for frames), changes its scene (its owner; the teacher for
// `default`), or deletes it (its owner or the teacher).
// Its owner, the teacher, and for `default` everyone.
bool canReadSession(const Identity& who, const Session& session);
enum class SessionAccess { Read, ReadWithKey, Write, Delete };
// The session named by the path's first match (running a pending default scene first), or
// answers and returns null: 404 when the requester may not read it (as for no such session),
// 403 when they may read but not change it.
std::shared_ptr<Session> sessionOr404(Service& service, const httplib::Request& req, httplib::Response& res,
                                      SessionAccess access, bool initialize = true);
// True when the session has a scene; else answers 409 no_scene.
bool requireScene(Session& session, httplib::Response& res);

// One of the shared one-shot render slots (renders and analyses queue for the device), held
// until the guard dies. takeRenderSlot answers 503 busy (and returns false) when none frees up
// within kRenderSlotWait or the server is stopping.
struct RenderSlotGuard {
  RenderSlots* slots = nullptr;
  RenderSlotGuard() = default;
  RenderSlotGuard(const RenderSlotGuard&) = delete;
  RenderSlotGuard& operator=(const RenderSlotGuard&) = delete;
  ~RenderSlotGuard() {
    if (slots) slots->release();
  }
};
// Also counts the render against the requester's --quota-renders (429 past it).
struct RenderQuotaGuard {
  OwnerCounter* counter = nullptr;
  std::string owner;
  RenderQuotaGuard() = default;
  RenderQuotaGuard(const RenderQuotaGuard&) = delete;
  RenderQuotaGuard& operator=(const RenderQuotaGuard&) = delete;
  ~RenderQuotaGuard() {
    if (counter) counter->release(owner);
  }
};
bool takeRenderSlot(Service& service, const httplib::Request& req, httplib::Response& res, RenderSlotGuard& guard,
                    RenderQuotaGuard& quota);

// Headers every image response carries.
void setFrameHeaders(httplib::Response& res, const FrameStats& stats);

// Image formats of frames (GET .../frame?format=, POST /api/render "format"): PNG is the
// tone-mapped display image; PFM and EXR are linear float radiance, never tone mapped.
enum class FrameFormat { Png, Pfm, Exr };
inline constexpr const char* kFrameFormatChoices = "png, pfm or exr";
std::optional<FrameFormat> frameFormatFromName(const std::string& name);
bool frameFormatIsFloat(FrameFormat format);  // PFM, EXR: needs Frame::rgba32f

// Encodes a frame (rgba8 for PNG, rgba32f for PFM/EXR); empty on an encoder failure.
std::vector<uint8_t> encodeFrame(const Frame& frame, FrameFormat format);

// Reads ?download= (absent, "0", "false": inline; "1", "true": attachment); on a bad value
// answers 400 `field: download` and returns nullopt.
std::optional<bool> readDownloadParam(const httplib::Request& req, httplib::Response& res);

// The image body with its Content-Type and `Content-Disposition: inline|attachment;
// filename="<stem>-<spp>spp.<ext>"` (`stem`: the session id, or "render"), plus the frame
// headers. An empty `bytes` (the encoder failed) answers 500.
void sendFrame(httplib::Response& res, const std::vector<uint8_t>& bytes, FrameFormat format, const FrameStats& stats,
               const std::string& stem, bool download);

}  // namespace brdfa::server
