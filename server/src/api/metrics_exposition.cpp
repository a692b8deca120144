// GET /metrics: the service's figures in the Prometheus text format (docs/deploy.md lists them).
// Names follow Prometheus' conventions: brdfa_ prefix, base units (seconds, bytes), _total on
// counters. Every family is always present, with zero values before any work.
#include "api/routes.h"
#include "metrics/prometheus_text.h"

namespace brdfa::server {

namespace {

// The render worker's channel (empty with --in-process): what crossing the process boundary
// costs, per operation.
void addWorkerChannel(PrometheusText& out, const RendererCounters& c) {
  // Each family's samples in one group, as the text format requires.
  out.family("brdfa_worker_requests_total", "counter", "Requests answered by the render worker, by operation.");
  for (const auto& [op, f] : c.channel) out.sample("brdfa_worker_requests_total", double(f.requests), {{"op", op}});
  out.family("brdfa_worker_bytes_total", "counter",
             "Bytes through the render worker's channel, by operation and direction (to or from the worker).");
  for (const auto& [op, f] : c.channel) {
    out.sample("brdfa_worker_bytes_total", double(f.bytesToWorker), {{"op", op}, {"direction", "to"}});
    out.sample("brdfa_worker_bytes_total", double(f.bytesFromWorker), {{"op", op}, {"direction", "from"}});
  }
  out.family("brdfa_worker_request_seconds_total", "counter",
             "Time of the render worker's requests, by operation and part: round_trip (written to reply read, "
             "here), queue (waiting for a worker thread) and serve (served by the worker).");
  for (const auto& [op, f] : c.channel) {
    out.sample("brdfa_worker_request_seconds_total", f.roundTripSeconds, {{"op", op}, {"part", "round_trip"}});
    out.sample("brdfa_worker_request_seconds_total", f.workerQueueSeconds, {{"op", op}, {"part", "queue"}});
    out.sample("brdfa_worker_request_seconds_total", f.workerServeSeconds, {{"op", op}, {"part", "serve"}});
  }
  out.family("brdfa_worker_in_flight_seconds_total", "counter",
             "Requests in flight to the render worker, integrated over time: its rate is the mean number at once.");
  out.sample("brdfa_worker_in_flight_seconds_total", c.channelInFlightSeconds);
  out.family("brdfa_worker_in_flight_max", "gauge", "The most requests in flight to the render worker at once.");
  out.sample("brdfa_worker_in_flight_max", double(c.channelMaxInFlight));
}

}  // namespace

std::string metricsText(const Service& service) {
  const RendererCounters c = service.renderer->counters();
  const uint64_t uploads = service.uploadMemory ? service.uploadMemory->taken() : 0;
  PrometheusText out;

  out.family("brdfa_replica_info", "gauge", "Always 1; the label is this server's --replica tag (empty without one).");
  out.sample("brdfa_replica_info", 1, {{"replica", service.config.replica}});
  out.family("brdfa_draining", "gauge", "1 while the server drains after SIGTERM (no new sessions or jobs), else 0.");
  out.sample("brdfa_draining", service.draining ? 1 : 0);

  out.family("brdfa_sessions", "gauge", "Interactive sessions held, the default one included.");
  out.sample("brdfa_sessions", static_cast<double>(service.sessions->list().size()));
  out.family("brdfa_streams", "gauge", "Open PNG stream clients.");
  out.sample("brdfa_streams", service.activeStreams.load());

  out.family("brdfa_samples_rendered_total", "counter", "Pixel samples rendered by sessions' progressive passes.");
  out.sample("brdfa_samples_rendered_total", static_cast<double>(service.metrics.samplesRendered.load()));
  out.family("brdfa_pass_duration_seconds", "histogram", "Wall time of one progressive pass of a session.");
  out.histogram("brdfa_pass_duration_seconds", service.metrics.passTime.snapshot());
  out.family("brdfa_queue_wait_seconds", "histogram",
             "Time a request waited for its slot: render (one-shot renders and analyses) or upload (upload checks).");
  out.histogram("brdfa_queue_wait_seconds", service.metrics.renderQueueWait.snapshot(), {{"queue", "render"}});
  out.histogram("brdfa_queue_wait_seconds", service.metrics.uploadQueueWait.snapshot(), {{"queue", "upload"}});

  out.family("brdfa_compiles_total", "counter", "GLSL to SPIR-V compiles (SPIR-V cache misses), by result.");
  out.sample("brdfa_compiles_total",
             static_cast<double>(c.glslCompiles - std::min(c.glslCompiles, c.glslCompileErrors)), {{"result", "ok"}});
  out.sample("brdfa_compiles_total", static_cast<double>(c.glslCompileErrors), {{"result", "error"}});
  out.family("brdfa_compile_duration_seconds", "histogram", "Wall time of one GLSL to SPIR-V compile.");
  out.histogram("brdfa_compile_duration_seconds", c.compileTime);
  out.family("brdfa_spirv_cache_hits_total", "counter", "Programs served from the SPIR-V cache instead of compiled.");
  out.sample("brdfa_spirv_cache_hits_total", static_cast<double>(c.spirvCacheHits), {{"cache", "memory"}});
  out.sample("brdfa_spirv_cache_hits_total", static_cast<double>(c.spirvDiskHits), {{"cache", "disk"}});
  out.family("brdfa_pipelines_created_total", "counter", "Shading pipelines built by the driver.");
  out.sample("brdfa_pipelines_created_total", static_cast<double>(c.pipelinesCreated));
  out.family("brdfa_render_worker_restarts_total", "counter",
             "Render workers killed and replaced (a pass, build or check past its budget).");
  out.sample("brdfa_render_worker_restarts_total", static_cast<double>(c.workerRestarts));
  addWorkerChannel(out, c);

  out.family("brdfa_rejections_total", "counter",
             "Requests answered with an error (HTTP status >= 400), by the error name of the JSON body.");
  for (const auto& [reason, n] : service.metrics.rejectionsByReason())
    out.sample("brdfa_rejections_total", static_cast<double>(n), {{"reason", reason}});
  out.family("brdfa_http_responses_total", "counter", "Responses sent, by HTTP status code.");
  for (const auto& [status, n] : service.metrics.responsesByStatus())
    out.sample("brdfa_http_responses_total", static_cast<double>(n), {{"code", std::to_string(status)}});

  out.family("brdfa_memory_used_bytes", "gauge",
             "Memory held against --max-memory: render targets, assets, programs, compiles, uploads in flight.");
  out.sample("brdfa_memory_used_bytes", static_cast<double>(c.memory.total() + uploads));
  out.family("brdfa_memory_budget_bytes", "gauge", "--max-memory (default half the machine's RAM).");
  out.sample("brdfa_memory_budget_bytes", static_cast<double>(service.memoryBudgetBytes));
  return out.text();
}

}  // namespace brdfa::server
