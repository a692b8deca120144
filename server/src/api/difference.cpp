// GET /api/sessions/{a}/difference?against={b}: the signed difference of two sessions' frames
// (the side-by-side view) as a PNG on a diverging colour map, or its figures
// as JSON (frame_difference.h).
#include <cmath>
#include <cstdio>

#include "api/routes.h"
#include "brdfa/frame_difference.h"
#include "brdfa/image_codec.h"
#include "http/http_errors.h"

namespace brdfa::server {

namespace {

// The session's latest linear frame with the stats of the moment it was read (waits for a
// first sample, like GET .../frame).
Result<Frame> linearFrame(Session& session) {
  Session::WaitOutcome outcome = Session::WaitOutcome::Reached;
  auto encoded = session.waitAndEncodeFrame(1, std::chrono::milliseconds(5000), true, outcome);
  if (outcome == Session::WaitOutcome::Stopped)
    return makeError(ErrorCode::NotFound, "session '" + session.id() + "' was stopped");
  if (outcome == Session::WaitOutcome::Failed)
    if (auto err = session.renderError()) return *err;
  if (!encoded) return encoded.takeError();
  Frame frame;
  if (!decodePfm(encoded->bytes, frame.width, frame.height, frame.rgba32f))
    return makeError(ErrorCode::Internal, "could not read back the frame of session '" + session.id() + "'");
  frame.stats = encoded->stats;
  return frame;
}

std::string number(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.6g", v);
  return s;
}

}  // namespace

void registerDifferenceRoutes(httplib::Server& server, Service& service) {
  server.Get("/api/sessions/([^/]+)/difference", [&service](const httplib::Request& req, httplib::Response& res) {
    const std::string format = req.has_param("format") ? req.get_param_value("format") : "png";
    if (format != "png" && format != "json")
      return sendError(res, ErrorCode::InvalidArgument, "format must be png or json", "format");
    if (!req.has_param("against"))
      return sendError(res, ErrorCode::InvalidArgument, "against: name the session to compare with", "against");
    double range = 0;
    if (req.has_param("range")) {
      const std::string text = req.get_param_value("range");
      char* end = nullptr;
      range = std::strtod(text.c_str(), &end);
      if (text.empty() || *end != '\0' || !(range > 0) || !std::isfinite(range))
        return sendError(res, ErrorCode::InvalidArgument, "range must be a positive number", "range");
    }
    auto a = sessionOr404(service, req, res, SessionAccess::Read);
    if (!a) return;
    auto b = service.sessions->find(req.get_param_value("against"));
    if (b && !canReadSession(requester(req), *b)) b = nullptr;  // someone else's: as if there were none
    if (!b)
      return sendError(res, ErrorCode::NotFound, "no session '" + req.get_param_value("against") + "'", "against");
    b->ensureInitialized();
    a->touch();
    b->touch();
    if (!requireScene(*a, res) || !requireScene(*b, res)) return;
    // Two waits at most: counted as frame waiters like GET .../frame.
    if (service.frameWaiters.fetch_add(1) >= service.maxFrameWaiters) {
      service.frameWaiters.fetch_sub(1);
      return sendError(res, ErrorCode::Busy, "too many requests waiting for samples; retry later");
    }
    Result<Frame> fa = linearFrame(*a);
    Result<Frame> fb = fa ? linearFrame(*b) : Result<Frame>(fa.error());
    service.frameWaiters.fetch_sub(1);
    if (!fa) return sendError(res, fa.error());
    if (!fb) return sendError(res, fb.error());
    Result<FrameDifference> diff = differenceOf(fa.value(), fb.value(), range);
    if (!diff) return sendError(res, diff.error());
    const FrameDifference& d = diff.value();
    res.set_header("Cache-Control", "no-store");
    if (format == "json") {
      nlohmann::json out{{"session", a->id()},
                         {"against", b->id()},
                         {"rel_rms", d.relRms},
                         {"rel_rms_error", d.relRmsError},
                         {"raw_rel_rms", d.rawRelRms},
                         {"noise_floor", d.noiseFloor},
                         {"pixels", d.pixels},
                         {"range", d.range},
                         {"spp", {fa->stats.spp, fb->stats.spp}},
                         {"rel_error", {*fa->stats.relError, *fb->stats.relError}}};
      return res.set_content(out.dump(), "application/json");
    }
    res.set_header("X-Rel-RMS", number(d.relRms));
    res.set_header("X-Rel-RMS-Error", number(d.relRmsError));
    res.set_header("X-Difference-Range", number(d.range));
    res.set_header("X-Samples", std::to_string(fa->stats.spp) + "," + std::to_string(fb->stats.spp));
    std::vector<uint8_t> png = encodePng(d.rgba8.data(), d.width, d.height);
    if (png.empty()) return sendError(res, ErrorCode::Internal, "could not encode the difference image");
    res.set_content(reinterpret_cast<const char*>(png.data()), png.size(), "image/png");
  });
}

}  // namespace brdfa::server
