// POST /api/render: one-shot, stateless. Body either {"scene": {...}, "spp": N, "format": ...,
// "brdf_source": ...} or the scene's own fields at the top level next to those keys.
#include <cmath>
#include <cstdio>

#include "api/routes.h"
#include "brdfa/image_codec.h"
#include "http/connection_guard.h"
#include "http/http_errors.h"
#include "http/request_body.h"

namespace brdfa::server {

namespace {

constexpr int kDefaultOneShotSpp = 64;
// Samples per pass when the request does not choose: fewer passes cost less overhead, and a
// bounded pass keeps one dispatch short on a GPU with a watchdog.
constexpr int kOneShotSamplesPerPass = 32;

const char* kRequestKeys[] = {"scene", "spp", "format", "brdf_source"};

bool isRequestKey(const std::string& key) {
  for (const char* k : kRequestKeys)
    if (key == k) return true;
  return false;
}

Result<int> readSpp(const nlohmann::json& v) {
  auto bad = [] {
    return makeError(ErrorCode::InvalidArgument,
                     "spp must be an integer in [1, " + std::to_string(kMaxOneShotSpp) + "]", "spp");
  };
  if (!v.is_number()) return bad();
  if (v.is_number_unsigned() || v.is_number_integer()) {
    long long n = v.is_number_unsigned()
                      ? static_cast<long long>(std::min<unsigned long long>(v.get<unsigned long long>(), 1ull << 62))
                      : v.get<long long>();
    if (n < 1 || n > kMaxOneShotSpp) return bad();
    return static_cast<int>(n);
  }
  double d = v.get<double>();
  if (!std::isfinite(d) || d != std::floor(d) || d < 1 || d > kMaxOneShotSpp) return bad();
  return static_cast<int>(d);
}

// Name (also the file extension) and Content-Type of each FrameFormat, in enum order.
struct FrameFormatInfo {
  FrameFormat format;
  const char* name;
  const char* contentType;
};
constexpr FrameFormatInfo kFrameFormats[] = {
    {FrameFormat::Png, "png", "image/png"},
    {FrameFormat::Pfm, "pfm", "application/x-portable-floatmap"},
    {FrameFormat::Exr, "exr", "image/x-exr"},
};

const FrameFormatInfo& infoOf(FrameFormat format) { return kFrameFormats[static_cast<int>(format)]; }

}  // namespace

std::optional<FrameFormat> frameFormatFromName(const std::string& name) {
  for (const FrameFormatInfo& f : kFrameFormats)
    if (name == f.name) return f.format;
  return std::nullopt;
}

bool frameFormatIsFloat(FrameFormat format) { return format != FrameFormat::Png; }

std::vector<uint8_t> encodeFrame(const Frame& f, FrameFormat format) {
  switch (format) {
    case FrameFormat::Pfm: return encodePfm(f.rgba32f.data(), f.width, f.height);
    case FrameFormat::Exr: return encodeExr(f.rgba32f.data(), f.width, f.height);
    case FrameFormat::Png: break;
  }
  return encodePng(f.rgba8.data(), f.width, f.height);
}

std::optional<bool> readDownloadParam(const httplib::Request& req, httplib::Response& res) {
  if (!req.has_param("download")) return false;
  const std::string v = req.get_param_value("download");
  if (v == "1" || v == "true") return true;
  if (v == "0" || v == "false") return false;
  sendError(res, ErrorCode::InvalidArgument, "download must be 1 or 0 (true or false)", "download");
  return std::nullopt;
}

void sendFrame(httplib::Response& res, const std::vector<uint8_t>& bytes, FrameFormat format, const FrameStats& stats,
               const std::string& stem, bool download) {
  if (bytes.empty())
    return sendError(res, ErrorCode::Internal, std::string("could not encode the frame as ") + infoOf(format).name);
  setFrameHeaders(res, stats);
  // `stem` is a session id ([0-9a-f]+ or "default") or "render": nothing to quote or escape.
  res.set_header("Content-Disposition", std::string(download ? "attachment" : "inline") + "; filename=\"" + stem + "-" +
                                            std::to_string(stats.spp) + "spp." + infoOf(format).name + "\"");
  res.set_content(reinterpret_cast<const char*>(bytes.data()), bytes.size(), infoOf(format).contentType);
}

bool takeRenderSlot(Service& service, const httplib::Request& req, httplib::Response& res, RenderSlotGuard& guard,
                    RenderQuotaGuard& quota) {
  // The person's own quota first: a student's script that fires renders in parallel waits in no
  // queue and holds no slot that classmates could use.
  const Identity& who = requester(req);
  const int limit = service.quotaFor(who, &Quotas::renders);
  int held = 0;
  if (!service.rendersInFlight.take(who.owner(), limit, held)) {
    sendQuotaExceeded(res, "renders", uint64_t(limit), uint64_t(held),
                      "you have " + std::to_string(held) +
                          " one-shot render(s) or analyses in flight, the most one "
                          "person may (--quota-renders " +
                          std::to_string(limit) + "); wait for it to finish");
    return false;
  }
  quota.counter = &service.rendersInFlight;
  quota.owner = who.owner();
  if (!service.renderSlots.acquire(kRenderSlotWait)) {
    sendError(res, ErrorCode::Busy,
              service.stopping ? "server is shutting down" : "too many renders in progress; retry later");
    return false;
  }
  guard.slots = &service.renderSlots;
  return true;
}

void registerRenderRoutes(httplib::Server& server, Service& service) {
  server.Post("/api/render", [&service](const httplib::Request& req, httplib::Response& res) {
    auto parsed = readJsonBody(req, res);
    if (!parsed) return;
    const nlohmann::json& body = *parsed;
    if (!body.is_object())
      return sendError(res, ErrorCode::InvalidArgument,
                       "the body must be a JSON object (a scene plus spp, format, brdf_source)");

    // Which form: a nested "scene" object, or the scene's fields inline.
    nlohmann::json sceneJson = nlohmann::json::object();
    if (auto it = body.find("scene"); it != body.end()) {
      for (auto kv = body.begin(); kv != body.end(); ++kv)
        if (!isRequestKey(kv.key()))
          return sendError(res, ErrorCode::InvalidArgument,
                           "unknown key '" + kv.key() + "' (with \"scene\" given, scene fields belong inside it)",
                           kv.key());
      sceneJson = *it;
      if (!sceneJson.is_object())
        return sendError(res, ErrorCode::InvalidArgument, "scene must be a JSON object", "scene");
    } else {
      for (auto kv = body.begin(); kv != body.end(); ++kv)
        if (!isRequestKey(kv.key())) sceneJson[kv.key()] = kv.value();
    }

    int spp = kDefaultOneShotSpp;
    if (auto it = body.find("spp"); it != body.end()) {
      Result<int> r = readSpp(*it);
      if (!r) return sendError(res, r.error());
      spp = r.value();
    }
    FrameFormat format = FrameFormat::Png;
    if (auto it = body.find("format"); it != body.end()) {
      std::optional<FrameFormat> f = it->is_string() ? frameFormatFromName(it->get<std::string>()) : std::nullopt;
      if (!f)
        return sendError(res, ErrorCode::InvalidArgument, std::string("format must be ") + kFrameFormatChoices,
                         "format");
      format = *f;
    }
    std::optional<bool> download = readDownloadParam(req, res);
    if (!download) return;
    std::shared_ptr<const BrdfDefinition> inlineBrdf;
    if (auto it = body.find("brdf_source"); it != body.end()) {
      if (!it->is_string())
        return sendError(res, ErrorCode::InvalidArgument, "brdf_source must be a string", "brdf_source");
      const std::string& text = it->get_ref<const std::string&>();
      if (text.size() > kMaxBrdfSource)
        return sendError(res, ErrorCode::PayloadTooLarge,
                         "brdf_source is larger than " + std::to_string(kMaxBrdfSource) + " bytes", "brdf_source");
      Result<BrdfDefinition> def = parseBrdf(text);
      if (!def) return sendError(res, def.error());
      inlineBrdf = std::make_shared<const BrdfDefinition>(std::move(def.value()));
    }

    bool spfGiven = sceneJson.contains("render") && sceneJson["render"].is_object() &&
                    sceneJson["render"].contains("samples_per_frame");
    Result<Scene> sceneResult = sceneFromJson(sceneJson, service.resolver(requester(req), inlineBrdf));
    if (!sceneResult) return sendError(res, sceneResult.error());
    Scene scene = std::move(sceneResult.value());
    scene.render.maxSamples = spp;
    if (!spfGiven) scene.render.samplesPerFrame = std::min(spp, kOneShotSamplesPerPass);

    // Bounded concurrency: renders share one device; a queue longer than the wait is refused.
    RenderQuotaGuard quota;
    RenderSlotGuard slot;
    if (!takeRenderSlot(service, req, res, slot, quota)) return;

    Result<std::unique_ptr<RenderView>> view = service.renderer->createView();
    if (!view) return sendError(res, view.error());
    RenderView& v = *view.value();
    if (Result<void> applied = v.setScene(scene); !applied) return sendError(res, applied.error());
    // Every pass adds at least one sample, so spp passes suffice; more means the renderer never
    // reports convergence, which must not turn into an endless loop on a worker thread.
    for (int passes = 0;; ++passes) {
      if (service.stopping) return sendError(res, ErrorCode::Unavailable, "server is shutting down");
      // A client that hung up gets nothing from the remaining passes: give the slot to the
      // next render now rather than when this one would have finished.
      if (service.connections && service.connections->peerClosed(req.remote_addr, req.remote_port)) {
        std::fprintf(stderr, "render: client %s:%d closed the connection; one-shot render stopped after %d passes\n",
                     req.remote_addr.c_str(), req.remote_port, passes);
        return sendError(res, ErrorCode::ClientClosed, "the client closed the connection before the render finished");
      }
      if (passes > spp)
        return sendError(res, ErrorCode::Internal,
                         "renderer did not converge after " + std::to_string(passes) + " passes");
      Result<FrameStats> pass = v.renderPass();
      if (!pass) return sendError(res, pass.error());
      if (pass.value().done()) break;
    }
    Result<Frame> frame = v.readFrame(frameFormatIsFloat(format));
    if (!frame) return sendError(res, frame.error());
    sendFrame(res, encodeFrame(frame.value(), format), format, frame.value().stats, "render", *download);
  });
}

}  // namespace brdfa::server
