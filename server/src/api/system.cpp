// Health, the request-body helpers, and the handlers that make sure no failure reaches a
// client as a dropped connection or an HTML page.
#include <cstdio>

#include "api/routes.h"
#include "http/http_errors.h"
#include "http/request_body.h"
#include "metrics/prometheus_text.h"

namespace brdfa::server {

std::optional<nlohmann::json> readJsonBody(const httplib::Request& req, httplib::Response& res) {
  if (req.body.size() > kMaxJsonBody) {
    sendError(res, ErrorCode::PayloadTooLarge,
              "request body is larger than " + std::to_string(kMaxJsonBody) + " bytes");
    return std::nullopt;
  }
  JsonBody parsed = parseJsonBody(req.body);
  if (!parsed.ok) {
    sendError(res, ErrorCode::BadJson, parsed.message);
    return std::nullopt;
  }
  return std::move(parsed.value);
}

std::optional<std::string> readBrdfTextBody(const httplib::Request& req, httplib::Response& res,
                                            const httplib::ContentReader& reader) {
  // Read here, not by httplib: Debian's libcpp-httplib refuses an
  // application/x-www-form-urlencoded body over 8 KiB (curl --data-binary's default type)
  // before a plain handler runs. Any content type is the text; a multipart form's one part is.
  std::string text;
  bool tooLarge = false, extraPart = false;
  size_t parts = 0;
  auto append = [&](const char* data, size_t n) {
    if (text.size() + n > kMaxBrdfSource) {
      tooLarge = true;
      return false;
    }
    text.append(data, n);
    return true;
  };
  const bool read = req.is_multipart_form_data()
                        ? reader([&](const httplib::MultipartFormData&) { return !(extraPart = ++parts > 1); }, append)
                        : reader(append);
  if (tooLarge) {
    sendError(res, ErrorCode::PayloadTooLarge,
              ".brdf text is larger than " + std::to_string(kMaxBrdfSource) + " bytes");
    return std::nullopt;
  }
  if (extraPart) {
    sendError(res, ErrorCode::InvalidArgument, "send the .brdf text as the body, or as the only part of a form",
              "body");
    return std::nullopt;
  }
  if (!read) {
    sendError(res, ErrorCode::InvalidArgument, "the request body could not be read", "body");
    return std::nullopt;
  }
  if (text.empty()) {
    sendError(res, ErrorCode::InvalidArgument, "the request body must be the .brdf text", "body");
    return std::nullopt;
  }
  return text;
}

void setFrameHeaders(httplib::Response& res, const FrameStats& stats) {
  res.set_header("X-Samples", std::to_string(stats.spp));
  char ms[32];
  std::snprintf(ms, sizeof(ms), "%.3f", stats.elapsedMs);
  res.set_header("X-Render-Ms", ms);
  res.set_header("X-Nan-Samples", std::to_string(stats.nanSamples));
  res.set_header("X-Scene-Version", std::to_string(stats.sceneVersion));
  res.set_header("Cache-Control", "no-store");
}

bool refuseWhileDraining(const Service& service, httplib::Response& res) {
  if (!service.draining) return false;
  res.set_header("Retry-After", "1");
  sendError(res, ErrorCode::Draining, "this replica is shutting down and takes no new sessions or jobs; retry");
  return true;
}

namespace {
// /api/health's `memory`: --max-memory and what holds it now, the renderer's uses and the
// uploads in flight here (docs/api.md, Health).
nlohmann::json memoryJson(const Service& service, const MemoryUsage& m) {
  const uint64_t uploads = service.uploadMemory->taken();
  return {{"budget_bytes", service.memoryBudgetBytes},
          {"used_bytes", m.total() + uploads},
          {"render_targets_bytes", m.renderTargets},
          {"renderer",
           {{"budget_bytes", m.budget},
            {"process_bytes", m.fixed},
            {"render_targets_bytes", m.renderTargets},
            {"assets_bytes", m.assets},
            {"transfers_bytes", m.transfers},
            {"programs_bytes", m.programs},
            {"compiles_bytes", m.compiles},
            {"dropped_bytes", m.droppedBytes},
            {"drops", m.drops},
            {"last_dropped", m.lastDropped}}},
          {"uploads", {{"budget_bytes", service.uploadMemory->capacity()}, {"in_flight_bytes", uploads}}}};
}
}  // namespace

void registerSystemRoutes(httplib::Server& server, Service& service) {
  // Responses httplib makes by itself (unknown route, 413, 414, ...) get the JSON error body;
  // responses a handler already filled pass through untouched.
  server.set_error_handler(
      httplib::Server::HandlerWithResponse([&service](const httplib::Request& req, httplib::Response& res) {
        if (!res.body.empty() || res.content_provider_) return httplib::Server::HandlerResponse::Unhandled;
        std::string message;
        switch (res.status) {
          case 404: message = "no such resource: " + req.method + " " + req.path; break;
          case 413:  // only httplib's own limit gets here: the largest body any route takes (an upload)
            message = "request body is larger than " + std::to_string(service.maxRequestBody()) + " bytes";
            break;
          default: message = "HTTP " + std::to_string(res.status) + " for " + req.method + " " + req.path; break;
        }
        sendStatusError(res, message);
        return httplib::Server::HandlerResponse::Handled;
      }));

  // A handler that throws (a bug, or std::bad_alloc) still answers with JSON.
  server.set_exception_handler([](const httplib::Request& req, httplib::Response& res, std::exception_ptr ep) {
    std::string what = "unknown exception";
    try {
      if (ep) std::rethrow_exception(ep);
    } catch (const std::exception& e) {
      what = e.what();
    } catch (...) {
    }
    std::fprintf(stderr, "error: %s %s threw: %s\n", req.method.c_str(), req.path.c_str(), what.c_str());
    sendError(res, ErrorCode::Internal, "internal error: " + what);
  });

  // Runs on every response before it is written (the logger runs after): counted here, a
  // response is in /metrics by the time its client reads it. Every response names the replica
  // that made it (the balancer's routing is checked by it).
  server.set_post_routing_handler([&service](const httplib::Request&, httplib::Response& res) {
    // The error's name, from sendError; internal, so it is taken off before the response goes.
    service.metrics.countResponse(res.status, res.get_header_value(kErrorNameHeader));
    res.headers.erase(kErrorNameHeader);
    if (!service.config.replica.empty()) res.set_header("X-Brdfa-Replica", service.config.replica);
  });

  server.set_logger([&service](const httplib::Request& req, const httplib::Response& res) {
    // A balancer probes every replica each second: its successful probes would drown the log.
    if (res.status < 300 && (req.path == "/api/health" || req.path == "/api/ready")) return;
    if (service.config.replica.empty())
      std::fprintf(stderr, "%s %s -> %d\n", req.method.c_str(), req.path.c_str(), res.status);
    else
      std::fprintf(stderr, "[%s] %s %s -> %d\n", service.config.replica.c_str(), req.method.c_str(), req.path.c_str(),
                   res.status);
  });

  // Readiness for a balancer: 503 while draining, so new work goes elsewhere (liveness is
  // /api/health, which answers to the end).
  server.Get("/api/ready", [&service](const httplib::Request&, httplib::Response& res) {
    if (refuseWhileDraining(service, res)) return;
    sendJson(res, {{"status", "ready"}, {"replica", service.config.replica}});
  });

  server.Get("/metrics", [&service](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(metricsText(service), PrometheusText::kContentType);
  });

  server.Get("/api/health", [&service](const httplib::Request&, httplib::Response& res) {
    const DeviceInfo& d = service.renderer->device();
    const RendererCounters c = service.renderer->counters();
    const HotLoadProgress hot = service.hotLoader.progress();
    sendJson(res,
             {{"status", "ok"},
              {"device", {{"name", d.name}, {"type", d.type}, {"driver", d.driver}, {"api_version", d.apiVersion}}},
              {"sessions", service.sessions->list().size()},
              {"streams", service.activeStreams.load()},
              {"compiler",
               {{"glsl_compiles", c.glslCompiles},
                {"spirv_cache_hits", c.spirvCacheHits},
                {"spirv_disk_hits", c.spirvDiskHits},
                {"pipelines_created", c.pipelinesCreated}}},
              {"memory", memoryJson(service, c.memory)},
              {"render_worker",
               {{"isolated", !service.config.inProcess},
                {"restarts", c.workerRestarts},
                {"quarantined_programs", c.quarantinedPrograms}}},
              {"hot_load",
               {{"enabled", hot.enabled},
                {"done", hot.done},
                {"brdfs", hot.brdfs},
                {"visited", hot.visited},
                {"pipelines", hot.pipelines},
                {"ms", hot.ms}}}});
  });
}

}  // namespace brdfa::server
