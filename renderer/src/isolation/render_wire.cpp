#include "isolation/render_wire.h"

#include <cstring>
#include <functional>

namespace brdfa {

// Field lists for nlohmann's generated conversions (enums travel as their integers). Only this
// file sees them: both ends of the wire are built from it.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(Diagnostic, line, column, severity, message)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(BrdfParam, name, type, min, max, defaultValue, line)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(BrdfClaims, declared, reciprocity, energyConservation, nonNegativity, line)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(ClaimVerdict, name, claimed, holds, measured)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(Camera, position, yaw, pitch, fov)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(EnvironmentSettings, name, intensity, rotation, visible)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(RenderSettings, width, height, samplesPerFrame, maxSamples, sampling, targetError,
                                   seed, exposure, toneMap, previewPass, firstSampleKernel)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(TextureBinding, name, srgb)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(DeviceInfo, name, type, driver, apiVersion)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(CompileInfo, warnings, compileMs, cached)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(MemoryUsage, budget, fixed, renderTargets, assets, transfers, programs, compiles,
                                   droppedBytes, drops, lastDropped)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(DurationHistogram, counts, sumSec, count)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(RendererCounters, glslCompiles, glslCompileErrors, compileTime, spirvCacheHits,
                                   spirvDiskHits, pipelinesCreated, memory, workerRestarts, quarantinedPrograms)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(BrdfCheckReport, evaluations, nanCount, infCount, negativeCount, maxAlbedo,
                                   maxAlbedoStdError, albedoAboveOne, maxReciprocityError, leftOut, worstReciprocity,
                                   firstBadValue, worstAlbedo, claims, ms)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(DirectionPair, light, view)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(AlbedoEstimate, mean, stdError, samples, nonFinite)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SamplerCheckConfig, normalLabel, normal, tangent, bitangent, view, viewDeg,
                                   viewAzimuthDeg)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SamplerConfigResult, config, rejected, maxValueMismatch, maxCellZ, albedoZ,
                                   maxPdfMismatch, maxLengthError, pdfBelowHorizon, chi2PValue, chi2Failure, worstCheck,
                                   worstValue, worstSeverity)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SamplerCheckReport, samples, rejected, maxValueMismatch, cellsTested, maxCellZ,
                                   maxAlbedoZ, chi2Run, minChi2PValue, chi2PValues, chi2Threshold, maxPdfMismatch,
                                   chi2Failure, maxLengthError, pdfBelowHorizon, configurations,
                                   samplesPerConfiguration, configs, worstConfig, worstCheck, worstValue, worstSeverity,
                                   worst, ms)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(EnvironmentSamplerReport, samples, cellChi2PValue, positionChi2PValue,
                                   maxSolidAngleZ, solidAngleBins, maxPdfMismatch, hostPdfMismatch, pdfMismatchFraction,
                                   maxLengthError, failure)

namespace render_wire {

using nlohmann::json;

// The hand-written conversions below list every field; a field added to one of these types
// must be added there too (then update the size here). x86-64 Linux, the one target built.
#if defined(__x86_64__) && defined(__linux__)
static_assert(sizeof(FrameStats) == 248, "FrameStats changed: update toJson/statsFromJson");
static_assert(sizeof(RendererOptions) == 264, "RendererOptions changed: update toJson/optionsFromJson");
static_assert(sizeof(SceneObject) == 192, "SceneObject changed: update toJson(Scene)/sceneFromJson");
#endif

std::string encodeHead(const nlohmann::json& head) {
  // CBOR, not JSON text: NaN and infinities (a check's worst value) survive it.
  std::string cbor;
  json::to_cbor(head, cbor);
  std::string out(sizeof(uint32_t), '\0');
  const uint32_t n = static_cast<uint32_t>(cbor.size());
  std::memcpy(out.data(), &n, sizeof n);
  out += cbor;
  return out;
}

std::string encode(const Message& message) { return encodeHead(message.head) + message.tail; }

bool decode(const std::string& frame, Message& message) {
  uint32_t n = 0;
  if (frame.size() < sizeof n) return false;
  std::memcpy(&n, frame.data(), sizeof n);
  if (frame.size() - sizeof n < n) return false;
  message.head = json::from_cbor(frame.begin() + sizeof n, frame.begin() + sizeof n + n, true, false);
  if (message.head.is_discarded()) return false;
  message.tail.assign(frame, sizeof n + n, std::string::npos);
  return true;
}

json toJson(const BrdfDefinition& brdf) {
  return json{{"format", brdf.format},
              {"params", brdf.params},
              {"shader", brdf.shader},
              {"shaderFirstLine", brdf.shaderFirstLine},
              {"sampleShader", brdf.sampleShader},
              {"sampleFirstLine", brdf.sampleFirstLine},
              {"warnings", brdf.warnings},
              {"claims", brdf.claims},
              {"measuredTable", brdf.measuredTable}};
}

BrdfDefinition brdfFromJson(const json& j) {
  BrdfDefinition b;
  j.at("format").get_to(b.format);
  j.at("params").get_to(b.params);
  j.at("shader").get_to(b.shader);
  j.at("shaderFirstLine").get_to(b.shaderFirstLine);
  j.at("sampleShader").get_to(b.sampleShader);
  j.at("sampleFirstLine").get_to(b.sampleFirstLine);
  j.at("warnings").get_to(b.warnings);
  j.at("claims").get_to(b.claims);
  j.at("measuredTable").get_to(b.measuredTable);
  return b;
}

std::string programKey(const BrdfDefinition& brdf) {
  // Line numbers change the #line directives, hence the SPIR-V; warnings do not matter.
  json j = toJson(brdf);
  j.erase("warnings");
  j.erase("measuredTable");  // a binding, not code: every measured BRDF runs one program
  char text[24];
  std::snprintf(text, sizeof text, "%016zx", std::hash<std::string>{}(j.dump()));
  return text;
}

json toJson(const Error& error) {
  return json{
      {"code", error.code}, {"message", error.message}, {"field", error.field}, {"diagnostics", error.diagnostics}};
}

Error errorFromJson(const json& j) {
  Error e;
  e.code = j.value("code", ErrorCode::Internal);
  e.message = j.value("message", std::string("the render worker sent a malformed error"));
  e.field = j.value("field", std::string());
  if (j.contains("diagnostics")) j.at("diagnostics").get_to(e.diagnostics);
  return e;
}

json toJson(const Scene& scene) {
  json objects = json::array();
  for (const SceneObject& o : scene.objects) {
    objects.push_back(json{{"mesh", o.mesh},
                           {"brdf", o.brdf ? toJson(*o.brdf) : json()},
                           {"brdfName", o.brdfName},
                           {"params", o.params},
                           {"translate", o.translate},
                           {"rotate", o.rotate},
                           {"scale", o.scale},
                           {"textures", o.textures}});
  }
  return json{
      {"camera", scene.camera}, {"environment", scene.environment}, {"render", scene.render}, {"objects", objects}};
}

Scene sceneFromJson(const json& j) {
  Scene s;
  j.at("camera").get_to(s.camera);
  j.at("environment").get_to(s.environment);
  j.at("render").get_to(s.render);
  for (const json& o : j.at("objects")) {
    SceneObject obj;
    o.at("mesh").get_to(obj.mesh);
    if (!o.at("brdf").is_null()) obj.brdf = std::make_shared<const BrdfDefinition>(brdfFromJson(o.at("brdf")));
    o.at("brdfName").get_to(obj.brdfName);
    o.at("params").get_to(obj.params);
    o.at("translate").get_to(obj.translate);
    o.at("rotate").get_to(obj.rotate);
    o.at("scale").get_to(obj.scale);
    o.at("textures").get_to(obj.textures);
    s.objects.push_back(std::move(obj));
  }
  return s;
}

json toJson(const FrameStats& f) {
  return json{{"spp", f.spp},
              {"passes", f.passes},
              {"elapsedMs", f.elapsedMs},
              {"lastPassMs", f.lastPassMs},
              {"nanSamples", f.nanSamples},
              {"relError", f.relError ? json(*f.relError) : json()},
              {"relErrorSpp", f.relErrorSpp},
              {"relErrorElapsedMs", f.relErrorElapsedMs},
              {"errorPixels", f.errorPixels},
              {"errorMeanLuminance", f.errorMeanLuminance},
              {"vertices", f.vertices},
              {"triangles", f.triangles},
              {"programBytes", f.programBytes},
              {"converged", f.converged},
              {"maxSamplesReached", f.maxSamplesReached},
              {"estimator", f.estimator},
              {"warnings", f.warnings},
              {"sceneVersion", f.sceneVersion},
              {"submissions", f.submissions},
              {"maxSubmissionMs", f.maxSubmissionMs},
              {"preview", f.preview},
              {"provisional", f.provisional},
              {"passInProgress", f.passInProgress},
              {"breakdown", json::array({f.breakdown.setupMs, f.breakdown.shadeMs, f.breakdown.edgeMs,
                                         f.breakdown.resolveMs, f.breakdown.otherMs})}};
}

FrameStats statsFromJson(const json& j) {
  FrameStats f;
  j.at("spp").get_to(f.spp);
  j.at("passes").get_to(f.passes);
  j.at("elapsedMs").get_to(f.elapsedMs);
  j.at("lastPassMs").get_to(f.lastPassMs);
  j.at("nanSamples").get_to(f.nanSamples);
  if (!j.at("relError").is_null()) f.relError = j.at("relError").get<double>();
  j.at("relErrorSpp").get_to(f.relErrorSpp);
  j.at("relErrorElapsedMs").get_to(f.relErrorElapsedMs);
  j.at("errorPixels").get_to(f.errorPixels);
  j.at("errorMeanLuminance").get_to(f.errorMeanLuminance);
  j.at("vertices").get_to(f.vertices);
  j.at("triangles").get_to(f.triangles);
  j.at("programBytes").get_to(f.programBytes);
  j.at("converged").get_to(f.converged);
  j.at("maxSamplesReached").get_to(f.maxSamplesReached);
  j.at("estimator").get_to(f.estimator);
  j.at("warnings").get_to(f.warnings);
  j.at("sceneVersion").get_to(f.sceneVersion);
  j.at("submissions").get_to(f.submissions);
  j.at("maxSubmissionMs").get_to(f.maxSubmissionMs);
  j.at("preview").get_to(f.preview);
  j.at("provisional").get_to(f.provisional);
  j.at("passInProgress").get_to(f.passInProgress);
  const json& b = j.at("breakdown");
  if (!b.is_array() || b.size() != 5) throw json::type_error::create(302, "breakdown: 5 numbers expected", &b);
  b[0].get_to(f.breakdown.setupMs);
  b[1].get_to(f.breakdown.shadeMs);
  b[2].get_to(f.breakdown.edgeMs);
  b[3].get_to(f.breakdown.resolveMs);
  b[4].get_to(f.breakdown.otherMs);
  return f;
}

json toJson(const RendererOptions& o) {
  // isolate is the caller's business: the worker always renders in its own process.
  return json{{"deviceName", o.deviceName},
              {"shaderDir", o.shaderDir},
              {"validation", o.validation},
              {"resolve", o.resolve},
              {"cacheDir", o.cacheDir},
              {"loadCache", o.loadCache},
              {"profilePasses", o.profilePasses},
              {"driverCacheDir", o.driverCacheDir},
              {"compileSeconds", o.compileSeconds},
              {"compileMemoryMiB", o.compileMemoryMiB},
              {"compileWorkers", o.compileWorkers},
              {"memoryBudgetBytes", o.memoryBudgetBytes},
              {"memoryBudgetLabel", o.memoryBudgetLabel},
              {"spareProcesses", o.spareProcesses},
              {"buildSeconds", o.buildSeconds},
              {"passSeconds", o.passSeconds},
              {"checkSeconds", o.checkSeconds},
              {"submissionTargetMs", o.submissionTargetMs},
              {"soloSubmissionTargetMs", o.soloSubmissionTargetMs},
              {"workerMemoryBytes", o.workerMemoryBytes}};
}

RendererOptions optionsFromJson(const json& j) {
  RendererOptions o;
  j.at("deviceName").get_to(o.deviceName);
  j.at("shaderDir").get_to(o.shaderDir);
  j.at("validation").get_to(o.validation);
  j.at("resolve").get_to(o.resolve);
  j.at("cacheDir").get_to(o.cacheDir);
  j.at("loadCache").get_to(o.loadCache);
  j.at("profilePasses").get_to(o.profilePasses);
  j.at("driverCacheDir").get_to(o.driverCacheDir);
  j.at("compileSeconds").get_to(o.compileSeconds);
  j.at("compileMemoryMiB").get_to(o.compileMemoryMiB);
  j.at("compileWorkers").get_to(o.compileWorkers);
  j.at("memoryBudgetBytes").get_to(o.memoryBudgetBytes);
  j.at("memoryBudgetLabel").get_to(o.memoryBudgetLabel);
  j.at("spareProcesses").get_to(o.spareProcesses);
  j.at("buildSeconds").get_to(o.buildSeconds);
  j.at("passSeconds").get_to(o.passSeconds);
  j.at("checkSeconds").get_to(o.checkSeconds);
  j.at("submissionTargetMs").get_to(o.submissionTargetMs);
  j.at("soloSubmissionTargetMs").get_to(o.soloSubmissionTargetMs);
  j.at("workerMemoryBytes").get_to(o.workerMemoryBytes);
  return o;
}

json toJson(const DeviceInfo& info) { return info; }
DeviceInfo deviceFromJson(const json& j) { return j.get<DeviceInfo>(); }
json toJson(const CompileInfo& info) { return info; }
CompileInfo compileInfoFromJson(const json& j) { return j.get<CompileInfo>(); }
json toJson(const RendererCounters& counters) { return counters; }
RendererCounters countersFromJson(const json& j) { return j.get<RendererCounters>(); }
json toJson(const std::vector<DirectionPair>& pairs) { return pairs; }
std::vector<DirectionPair> pairsFromJson(const json& j) { return j.get<std::vector<DirectionPair>>(); }
json toJson(const std::vector<AlbedoEstimate>& albedo) { return albedo; }
std::vector<AlbedoEstimate> albedoFromJson(const json& j) { return j.get<std::vector<AlbedoEstimate>>(); }
json toJson(const BrdfCheckReport& report) { return report; }
BrdfCheckReport brdfReportFromJson(const json& j) { return j.get<BrdfCheckReport>(); }
json toJson(const SamplerCheckReport& report) { return report; }
SamplerCheckReport samplerReportFromJson(const json& j) { return j.get<SamplerCheckReport>(); }
json toJson(const EnvironmentSamplerReport& report) { return report; }
EnvironmentSamplerReport environmentReportFromJson(const json& j) { return j.get<EnvironmentSamplerReport>(); }

}  // namespace render_wire
}  // namespace brdfa
