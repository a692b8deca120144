// Interactive sessions: create/list/delete, scene get/put/patch, frames, the PNG stream, stats.
#include <charconv>
#include <cmath>
#include <string_view>

#include "api/routes.h"
#include "brdfa/image_codec.h"
#include "http/http_body.h"
#include "http/http_errors.h"
#include "http/request_body.h"
#include "jobs/convergence.h"

namespace brdfa::server {

namespace {

using namespace std::chrono_literals;

nlohmann::json targetErrorJson(const RenderSettings& render) {
  return render.targetError > 0 ? nlohmann::json(render.targetError) : nlohmann::json(nullptr);
}

nlohmann::json statsToJson(const FrameStats& s, const std::optional<Error>& renderError, const RenderSettings& render) {
  nlohmann::json out{{"spp", s.spp},
                     {"elapsed_ms", s.elapsedMs},
                     {"ms_per_frame", s.lastPassMs},
                     // Passes per second at the latest pass's pace (a pass is one progressive frame).
                     {"fps", s.lastPassMs > 0 ? 1000.0 / s.lastPassMs : 0.0},
                     {"vertices", s.vertices},
                     {"triangles", s.triangles},
                     {"program_bytes", s.programBytes},
                     {"rel_error", nullptr},
                     {"nan_samples", s.nanSamples},
                     {"passes", s.passes},
                     // spp 1 by the preview kernel, replaced by the first pass of the scene's program.
                     {"provisional", s.provisional},
                     // The last pass: its wall time, and the queue submissions it was split into.
                     {"last_pass_ms", s.lastPassMs},
                     {"last_pass_submissions", s.submissions},
                     {"last_pass_max_submission_ms", s.maxSubmissionMs},
                     // rel_error <= render.target_error (only with a target, from kMinSppForTarget spp).
                     {"converged", s.converged},
                     {"max_samples_reached", s.maxSamplesReached},
                     {"done", s.done()},  // either: no more passes run until the scene changes
                     {"target_error", targetErrorJson(render)},
                     {"sampling", samplingModeName(render.sampling)},
                     {"estimator", s.estimator},
                     {"warnings", s.warnings},
                     {"rel_error_spp", s.relErrorSpp},
                     {"rel_error_elapsed_ms", s.relErrorElapsedMs},
                     {"scene_version", s.sceneVersion}};
  if (s.relError && std::isfinite(*s.relError)) out["rel_error"] = *s.relError;
  if (renderError) out["error"] = {{"error", errorCodeName(renderError->code)}, {"message", renderError->message}};
  return out;
}

// Validates `json` and applies it under the held update lock; answers with the full scene.
void applySceneJson(Service& service, const Identity& who, Session& session, std::unique_lock<std::mutex>& lock,
                    const nlohmann::json& json, httplib::Response& res) {
  std::vector<std::string> notes;
  Result<Scene> scene = sceneFromJson(json, service.resolver(who), &notes);
  if (!scene) return sendError(res, scene.error());
  nlohmann::json full = sceneToJson(scene.value(), notes);
  Result<void> applied = session.applyScene(lock, scene.value(), full);
  if (!applied) return sendError(res, applied.error());
  sendJson(res, full);
}

// ?min_spp=N: a non-negative integer; values beyond 64 bits saturate (max_samples caps them).
std::optional<uint64_t> parseMinSpp(const std::string& text) {
  if (text.empty() || text.size() > 40) return std::nullopt;
  uint64_t v = 0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ptr != text.data() + text.size()) return std::nullopt;
  if (ec == std::errc::result_out_of_range) return UINT64_MAX;
  if (ec != std::errc()) return std::nullopt;
  return v;
}

// ?target=X for /convergence: a relative error in (0, 1), like render.target_error.
std::optional<double> parseTargetError(const std::string& text) {
  if (text.empty() || text.size() > 40) return std::nullopt;
  double v = 0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v) || v <= 0 || v >= 1)
    return std::nullopt;
  return v;
}

// A number as the JSON answer writes it (shortest form that reads back the same double), so
// the CSV and the JSON carry identical values.
std::string csvNumber(double v) { return nlohmann::json(v).dump(); }

std::string convergenceCsv(const std::vector<ConvergencePoint>& points) {
  std::string out = "elapsed_ms,spp,rel_error,passes\n";
  for (const ConvergencePoint& p : points)
    out += csvNumber(p.elapsedMs) + "," + std::to_string(p.spp) + "," + csvNumber(p.relError) + "," +
           std::to_string(p.passes) + "\n";
  return out;
}

nlohmann::json convergenceJson(const Session::Convergence& c, std::optional<double> target, size_t maxPoints) {
  nlohmann::json points = nlohmann::json::array();
  for (const ConvergencePoint& p : thinLogTime(c.points, maxPoints))
    points.push_back({{"elapsed_ms", p.elapsedMs}, {"spp", p.spp}, {"rel_error", p.relError}, {"passes", p.passes}});
  nlohmann::json out{{"points", std::move(points)},
                     {"fit", nullptr},
                     {"target_error", target ? nlohmann::json(*target) : nlohmann::json(nullptr)},
                     {"predicted_ms", nullptr},
                     {"sampling", samplingModeName(c.render.sampling)},
                     {"estimator", c.stats.estimator},
                     {"warnings", c.stats.warnings},
                     {"spp", c.stats.spp},
                     {"passes", c.stats.passes},
                     {"elapsed_ms", c.stats.elapsedMs},
                     {"converged", c.stats.converged},
                     {"max_samples_reached", c.stats.maxSamplesReached},
                     {"done", c.stats.done()},
                     {"scene_version", c.stats.sceneVersion},
                     {"max_points", ConvergenceSeries::kMaxPoints}};
  // The fit always uses the whole series, whatever max_points thinned the answer to.
  if (std::optional<LogLogFit> fit = fitLogLog(c.points, c.firstPassMs)) {
    out["fit"] = {{"slope", fit->slope},
                  {"intercept", fit->intercept},
                  {"points_used", fit->pointsUsed},
                  {"time_offset_ms", fit->offsetMs}};
    if (target)
      if (std::optional<double> ms = predictMs(*fit, *target)) out["predicted_ms"] = *ms;
  }
  return out;
}

struct StreamState {
  uint64_t lastSeq = 0;
  // The scene version in place when the client connected: older frames (still being encoded
  // then) are not sent to it. A client already streaming gets them: they are the latest image.
  uint64_t minSceneVersion = 0;
  bool opened = false;  // the first part's boundary and headers were sent
  Session::Clock::time_point lastSent = Session::Clock::now();
};

// One call of the stream's content provider: sends the next part when there is a newer frame,
// ends the body when the session or server stops, else returns after a short wait (httplib
// checks for server shutdown between calls). false drops the client.
bool writeNextPart(Service& service, Session& session, StreamState& state, httplib::DataSink& sink) {
  auto finished = [&] { return service.stopping.load() || session.stopped(); };
  if (finished()) {
    sink.done();
    return true;
  }
  std::optional<StreamFrame> frame = session.waitForStreamFrame(state.lastSeq, 250ms, state.minSceneVersion);
  if (!frame) {
    if (finished()) {
      sink.done();
      return true;
    }
    // Nothing new (converged or idle). Resend the last frame now and then: the write is how a
    // client that went away is noticed, freeing its worker thread.
    if (Session::Clock::now() - state.lastSent < 10s) return true;
    frame = session.latestStreamFrame();
    if (!frame) return true;
  }
  const std::vector<uint8_t>& png = *frame->png;
  // Each part is followed at once by the next part's boundary and headers. Chromium's multipart
  // parser finishes a part (and shows the image) only when it has parsed the headers of the
  // next one: sent with the next frame, they would keep every frame off screen until the next
  // frame arrives, and the converged frame until the 10 s resend. So the headers cannot hold
  // per-frame data; the sample count is in the PNG (tEXt "brdfa:spp").
  static constexpr std::string_view kPartHeaders = "--frame\r\nContent-Type: image/png\r\n\r\n";
  if (!state.opened && !sink.write(kPartHeaders.data(), kPartHeaders.size())) return false;
  state.opened = true;
  if (!sink.write(reinterpret_cast<const char*>(png.data()), png.size())) return false;
  if (!sink.write("\r\n", 2) || !sink.write(kPartHeaders.data(), kPartHeaders.size())) return false;
  state.lastSeq = frame->seq;
  state.lastSent = Session::Clock::now();
  return true;
}

// Whose a session is, for the teacher only.
void addOwner(nlohmann::json& out, const SessionOwnership& ownership, const Identity& who) {
  if (!who.teacher()) return;
  out["owner"] = ownership.user.empty() ? nlohmann::json(nullptr) : nlohmann::json(ownership.user);
  out["owner_display_name"] = ownership.displayName;
}

// What a reader of the session sees of it: the teacher also whose it is.
nlohmann::json sessionSummary(Session& s, const Identity& who, const std::string& replica) {
  nlohmann::json out{{"id", s.id()},
                     {"stats", statsToJson(s.stats(), s.renderError(), s.renderSettings())},
                     {"stream_clients", s.streamClients()},
                     {"view_key", s.ownership().viewKey}};
  if (!replica.empty()) out["replica"] = replica;
  addOwner(out, s.ownership(), who);
  return out;
}

// A session of another replica: its stats live there (GET /api/sessions/{id} through the
// balancer reaches it).
nlohmann::json remoteSummary(const RemoteSession& s, const Identity& who) {
  nlohmann::json out{{"id", s.id},
                     {"stats", nullptr},
                     {"stream_clients", nullptr},
                     {"view_key", s.ownership.viewKey},
                     {"replica", s.replica}};
  addOwner(out, s.ownership, who);
  return out;
}

// How many sessions `who` holds on the other replicas of this data folder.
size_t sessionsElsewhere(Service& service, const Identity& who) {
  if (!service.directory) return 0;
  size_t n = 0;
  for (const RemoteSession& s : service.directory->others()) n += s.ownership.user == who.owner();
  return n;
}

}  // namespace

bool canReadSession(const Identity& who, const Session& s) {
  return canRead(who, s.owner(), s.id() == kDefaultSessionId);
}

std::shared_ptr<Session> sessionOr404(Service& service, const httplib::Request& req, httplib::Response& res,
                                      SessionAccess access, bool initialize) {
  std::string id = req.matches[1];
  auto session = service.sessions->find(id);
  const Identity& who = requester(req);
  // Someone else's session answers exactly as one that does not exist.
  const bool mayRead =
      session && (canReadSession(who, *session) || (access == SessionAccess::ReadWithKey && hasViewKey(req, *session)));
  if (!mayRead && !requesterKnown(req)) {  // a view-key read without the right key: as any tokenless request
    res.set_header("WWW-Authenticate", "Bearer realm=\"brdfa\"");
    sendError(res, ErrorCode::Unauthorized,
              "this key does not read session '" + id + "'; send a token or the view key");
    return nullptr;
  }
  if (!mayRead) {
    sendError(res, ErrorCode::NotFound, "no session '" + id + "'", "session");
    return nullptr;
  }
  if (access == SessionAccess::Write && !canWrite(who, session->owner())) {
    sendError(res, ErrorCode::Forbidden,
              session->id() == kDefaultSessionId ? "only the teacher changes the default session; make your own "
                                                   "(POST /api/sessions)"
                                                 : "only its owner changes session '" + id + "'",
              "session");
    return nullptr;
  }
  if (initialize) session->ensureInitialized();
  return session;
}

bool requireScene(Session& session, httplib::Response& res) {
  if (session.hasScene()) return true;
  sendError(res, ErrorCode::NoScene, "session '" + session.id() + "' has no scene yet; PUT one first");
  return false;
}

namespace {

void listSessions(Service& service, const httplib::Request& req, httplib::Response& res) {
  const Identity& who = requester(req);
  nlohmann::json list = nlohmann::json::array();
  for (auto& s : service.sessions->list())
    if (canReadSession(who, *s)) list.push_back(sessionSummary(*s, who, service.config.replica));
  if (service.directory)
    for (const RemoteSession& s : service.directory->others())
      if (canRead(who, s.ownership.user)) list.push_back(remoteSummary(s, who));
  sendJson(res, list);
}

void createSession(Service& service, const httplib::Request& req, httplib::Response& res) {
  if (refuseWhileDraining(service, res)) return;
  nlohmann::json body = nlohmann::json::object();
  if (!req.body.empty()) {
    auto parsed = readJsonBody(req, res);
    if (!parsed) return;
    body = std::move(*parsed);
  }
  // Validated before the session exists, so a bad scene leaves nothing behind.
  const Identity& who = requester(req);
  std::vector<std::string> notes;
  Result<Scene> scene = sceneFromJson(body, service.resolver(who), &notes);
  if (!scene) return sendError(res, scene.error());
  const int quota = service.quotaFor(who, &Quotas::sessions);
  // The quota is the person's, not the replica's: sessions they hold on other replicas count.
  const size_t elsewhere = quota > 0 ? sessionsElsewhere(service, who) : 0;
  SessionManager::Created created;
  if (quota > 0 && elsewhere >= size_t(quota))
    created.quotaFull = true;
  else
    created =
        service.sessions->create({}, SessionOwnership{who.owner(), who.displayName, {}}, size_t(quota) - elsewhere);
  if (created.quotaFull) {
    const size_t used = created.ownerSessions + elsewhere;
    return sendQuotaExceeded(res, "sessions", uint64_t(quota), used,
                             "you have " + std::to_string(used) +
                                 " sessions, the most one person may have (--quota-sessions " + std::to_string(quota) +
                                 "); delete one (DELETE /api/sessions/{id}) or close a tab");
  }
  if (created.full)
    return sendError(res, ErrorCode::TooManySessions,
                     "at most " + std::to_string(service.sessions->maxSessions()) + " sessions; delete one first");
  if (!created.session) return sendError(res, *created.error);
  nlohmann::json full = sceneToJson(scene.value(), notes);
  {
    auto lock = created.session->beginSceneUpdate(false);
    Result<void> applied = created.session->applyScene(lock, scene.value(), full);
    if (!applied) {
      lock.unlock();
      service.sessions->remove(created.session->id());
      return sendError(res, applied.error());
    }
  }
  res.set_header("Location", "/api/sessions/" + created.session->id());
  sendJson(res, {{"id", created.session->id()}, {"view_key", created.session->ownership().viewKey}, {"scene", full}},
           201);
}

void getSession(Service& service, const httplib::Request& req, httplib::Response& res) {
  auto session = sessionOr404(service, req, res, SessionAccess::Read);
  if (!session) return;
  nlohmann::json body = sessionSummary(*session, requester(req), service.config.replica);
  body["scene"] = session->sceneJson();
  sendJson(res, body);
}

void deleteSession(Service& service, const httplib::Request& req, httplib::Response& res) {
  std::string id = req.matches[1];
  if (auto session = service.sessions->find(id); session && id != kDefaultSessionId) {
    const Identity& who = requester(req);
    if (!canReadSession(who, *session))
      return sendError(res, ErrorCode::NotFound, "no session '" + id + "'", "session");
    if (!canDelete(who, session->owner()))
      return sendError(res, ErrorCode::Forbidden, "only its owner or the teacher deletes session '" + id + "'",
                       "session");
  }
  switch (service.sessions->remove(id)) {
    case SessionManager::RemoveOutcome::Removed: res.status = 204; return;
    case SessionManager::RemoveOutcome::NotFound:
      return sendError(res, ErrorCode::NotFound, "no session '" + id + "'", "session");
    case SessionManager::RemoveOutcome::Protected:
      return sendError(res, ErrorCode::Conflict, "the default session cannot be deleted", "session");
  }
}

void getScene(Service& service, const httplib::Request& req, httplib::Response& res) {
  auto session = sessionOr404(service, req, res, SessionAccess::Read);
  if (!session || !requireScene(*session, res)) return;
  sendJson(res, session->sceneJson());
}

void putScene(Service& service, const httplib::Request& req, httplib::Response& res) {
  auto session = sessionOr404(service, req, res, SessionAccess::Write, /*initialize=*/false);
  if (!session) return;
  auto body = readJsonBody(req, res);
  if (!body) return;
  auto lock = session->beginSceneUpdate(false);  // replaced anyway: no need for the default
  applySceneJson(service, requester(req), *session, lock, *body, res);
}

// RFC 7386 JSON merge patch onto the current (full) scene JSON, then validated as a whole.
// Arrays are replaced, not merged: to change one object, send the whole "objects" array.
void patchScene(Service& service, const httplib::Request& req, httplib::Response& res) {
  auto session = sessionOr404(service, req, res, SessionAccess::Write, /*initialize=*/false);
  if (!session) return;
  auto patch = readJsonBody(req, res);
  if (!patch) return;
  auto lock = session->beginSceneUpdate(true);
  nlohmann::json merged = session->sceneJson();
  if (merged.is_null()) merged = nlohmann::json::object();
  merged.merge_patch(*patch);
  applySceneJson(service, requester(req), *session, lock, merged, res);
}

void getStats(Service& service, const httplib::Request& req, httplib::Response& res) {
  auto session = sessionOr404(service, req, res, SessionAccess::Read);
  if (!session) return;
  session->touch();  // a client polling stats is watching
  sendJson(res, statsToJson(session->stats(), session->renderError(), session->renderSettings()));
}

// Error against render time since the last accumulation restart (convergence.h): JSON with
// the log-log fit, or ?format=csv. ?target=X predicts when rel_error reaches X (default: the
// scene's render.target_error); ?max_points=N thins the answer evenly in log-time.
void getConvergence(Service& service, const httplib::Request& req, httplib::Response& res) {
  const std::string format = req.has_param("format") ? req.get_param_value("format") : "json";
  if (format != "json" && format != "csv")
    return sendError(res, ErrorCode::InvalidArgument, "format must be json or csv", "format");
  std::optional<double> target;
  if (req.has_param("target")) {
    target = parseTargetError(req.get_param_value("target"));
    if (!target) return sendError(res, ErrorCode::InvalidArgument, "target must be a number in (0, 1)", "target");
  }
  size_t maxPoints = ConvergenceSeries::kMaxPoints;
  if (req.has_param("max_points")) {
    auto parsed = parseMinSpp(req.get_param_value("max_points"));
    if (!parsed || *parsed < 2 || *parsed > ConvergenceSeries::kMaxPoints)
      return sendError(res, ErrorCode::InvalidArgument,
                       "max_points must be an integer in [2, " + std::to_string(ConvergenceSeries::kMaxPoints) + "]",
                       "max_points");
    maxPoints = static_cast<size_t>(*parsed);
  }
  auto session = sessionOr404(service, req, res, SessionAccess::Read);
  if (!session) return;
  session->touch();  // a client following the curve is watching
  if (!requireScene(*session, res)) return;
  Session::Convergence c = session->convergence();
  if (!target && c.render.targetError > 0) target = c.render.targetError;
  res.set_header("Cache-Control", "no-store");
  if (format == "csv") return sendBody(res, convergenceCsv(thinLogTime(c.points, maxPoints)), "text/csv");
  sendJson(res, convergenceJson(c, target, maxPoints));
}

void getFrame(Service& service, const httplib::Request& req, httplib::Response& res) {
  std::optional<FrameFormat> format =
      frameFormatFromName(req.has_param("format") ? req.get_param_value("format") : "png");
  if (!format)
    return sendError(res, ErrorCode::InvalidArgument, std::string("format must be ") + kFrameFormatChoices, "format");
  std::optional<bool> download = readDownloadParam(req, res);
  if (!download) return;
  // Default 1: "the latest frame" always has at least one sample in it (not a black image
  // right after a scene change). min_spp=0 answers at once with whatever there is.
  uint64_t minSpp = 1;
  if (req.has_param("min_spp")) {
    auto parsed = parseMinSpp(req.get_param_value("min_spp"));
    if (!parsed) return sendError(res, ErrorCode::InvalidArgument, "min_spp must be a non-negative integer", "min_spp");
    minSpp = *parsed;
  }
  auto session = sessionOr404(service, req, res, SessionAccess::ReadWithKey);
  if (!session) return;
  session->touch();
  if (!requireScene(*session, res)) return;
  // Only waits that can last hold a worker; an answer available now never counts.
  if (service.frameWaiters.fetch_add(1) >= service.maxFrameWaiters) {
    service.frameWaiters.fetch_sub(1);
    return sendError(res, ErrorCode::Busy,
                     "too many requests waiting for samples (at most " + std::to_string(service.maxFrameWaiters) +
                         "); retry later or without min_spp");
  }
  // The session encodes PNG or PFM; EXR is made from the PFM's floats (the same radiance).
  const bool pfm = frameFormatIsFloat(*format);
  Session::WaitOutcome outcome = Session::WaitOutcome::Reached;
  auto frame = session->waitAndEncodeFrame(minSpp, kFrameWait, pfm, outcome);
  service.frameWaiters.fetch_sub(1);
  switch (outcome) {
    case Session::WaitOutcome::Stopped:
      return sendError(res, ErrorCode::Unavailable,
                       "the session was stopped (deleted, or the server is shutting down)");
    case Session::WaitOutcome::Failed:
      if (auto err = session->renderError()) return sendError(res, *err);
      break;
    case Session::WaitOutcome::Reached:
    case Session::WaitOutcome::TimedOut:  // bounded wait: answer with what there is
      break;
  }
  if (!frame) return sendError(res, frame.error());
  if (*format == FrameFormat::Exr) {
    Frame linear;
    if (!decodePfm(frame->bytes, linear.width, linear.height, linear.rgba32f))
      return sendError(res, ErrorCode::Internal, "could not read back the frame's float radiance");
    frame->bytes = encodeFrame(linear, FrameFormat::Exr);
  }
  sendFrame(res, frame->bytes, *format, frame->stats, session->id(), *download);
}

// multipart/x-mixed-replace: each part is one PNG. The render thread publishes at most ~30
// frames/s (and always the converged one); each client sends the latest when it is newer
// than what it sent last, so a slow client skips frames and never holds up rendering.
void streamFrames(Service& service, const httplib::Request& req, httplib::Response& res) {
  auto session = sessionOr404(service, req, res, SessionAccess::ReadWithKey);
  if (!session) return;
  if (service.activeStreams.fetch_add(1) >= service.maxStreams) {
    service.activeStreams.fetch_sub(1);
    return sendError(res, ErrorCode::TooManyStreams,
                     "at most " + std::to_string(service.maxStreams) + " concurrent streams");
  }
  session->addStreamClient();
  auto state = std::make_shared<StreamState>();
  state->minSceneVersion = session->stats().sceneVersion;
  res.set_header("Cache-Control", "no-store");
  // Chunked: HTTP/1.1 framing with an explicit end when the stream stops (server shutdown,
  // session deleted), instead of a body that ends only when the connection closes.
  res.set_chunked_content_provider(
      "multipart/x-mixed-replace; boundary=frame",
      [&service, session, state](size_t, httplib::DataSink& sink) -> bool {
        // Runs outside httplib's handler try/catch: an exception here would end the process.
        try {
          return writeNextPart(service, *session, *state, sink);
        } catch (const std::exception&) {
          return false;  // drops this client; the session and other clients go on
        }
      },
      [&service, session](bool) {
        session->removeStreamClient();
        service.activeStreams.fetch_sub(1);
      });
}

}  // namespace

void registerSessionRoutes(httplib::Server& server, Service& service) {
  server.Get("/api/sessions", withService(service, listSessions));
  server.Post("/api/sessions", withService(service, createSession));
  server.Get("/api/sessions/([^/]+)", withService(service, getSession));
  server.Delete("/api/sessions/([^/]+)", withService(service, deleteSession));
  server.Get("/api/sessions/([^/]+)/scene", withService(service, getScene));
  server.Put("/api/sessions/([^/]+)/scene", withService(service, putScene));
  server.Patch("/api/sessions/([^/]+)/scene", withService(service, patchScene));
  server.Get("/api/sessions/([^/]+)/stats", withService(service, getStats));
  server.Get("/api/sessions/([^/]+)/convergence", withService(service, getConvergence));
  server.Get("/api/sessions/([^/]+)/frame", withService(service, getFrame));
  server.Get("/api/sessions/([^/]+)/stream", withService(service, streamFrames));
}

}  // namespace brdfa::server
