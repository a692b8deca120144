// GET /metrics: the service's figures in the Prometheus text format (docs/deploy.md lists them).
// Names follow Prometheus' conventions: brdfa_ prefix, base units (seconds, bytes), _total on
// counters. Every family is always present, with zero values before any work.
#include "brdfa_server/prometheus_text.h"
#include "routes.h"

namespace brdfa::server {

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
  out.sample("brdfa_compiles_total", static_cast<double>(c.glslCompiles - std::min(c.glslCompiles, c.glslCompileErrors)),
             {{"result", "ok"}});
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
