#include "core/scene_check.h"

#include <cmath>
#include <string>

namespace brdfa {

namespace {

Error invalid(const std::string& field, const std::string& why) {
  return makeError(ErrorCode::InvalidArgument, field + ": " + why, field);
}

bool finite3(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

}  // namespace

const char* samplingModeName(SamplingMode mode) {
  switch (mode) {
    case SamplingMode::Uniform: return "uniform";
    case SamplingMode::Brdf: return "brdf";
    case SamplingMode::Environment: return "environment";
    case SamplingMode::Mis: return "mis";
    default: return "cosine";
  }
}

bool samplingModeFromName(const std::string& name, SamplingMode& mode) {
  for (SamplingMode m :
       {SamplingMode::Cosine, SamplingMode::Uniform, SamplingMode::Brdf, SamplingMode::Environment, SamplingMode::Mis})
    if (name == samplingModeName(m)) {
      mode = m;
      return true;
    }
  return false;
}

const char* toneMapName(ToneMap toneMap) {
  switch (toneMap) {
    case ToneMap::Reinhard: return "reinhard";
    case ToneMap::Aces: return "aces";
    default: return "clamp";
  }
}

bool toneMapFromName(const std::string& name, ToneMap& toneMap) {
  for (ToneMap t : {ToneMap::Clamp, ToneMap::Reinhard, ToneMap::Aces})
    if (name == toneMapName(t)) {
      toneMap = t;
      return true;
    }
  return false;
}

Result<void> checkScene(const Scene& s) {
  const RenderSettings& r = s.render;
  if (r.width < kMinImageSize || r.width > kMaxImageSize) return invalid("render.width", "must be between 16 and 4096");
  if (r.height < kMinImageSize || r.height > kMaxImageSize)
    return invalid("render.height", "must be between 16 and 4096");
  if (r.samplesPerFrame < 1 || r.samplesPerFrame > kMaxSamplesPerFrame)
    return invalid("render.samples_per_frame", "must be between 1 and 1024");
  if (r.maxSamples < 1 || r.maxSamples > kMaxTotalSamples)
    return invalid("render.max_samples", "must be between 1 and 1048576");
  if (!std::isfinite(r.exposure) || std::fabs(r.exposure) > 64)
    return invalid("render.exposure", "must be within +-64");

  const Camera& c = s.camera;
  if (!finite3(c.position) || std::fabs(c.position[0]) > 1e6f || std::fabs(c.position[1]) > 1e6f ||
      std::fabs(c.position[2]) > 1e6f)
    return invalid("camera.position", "must be finite and within 1e6");
  if (!std::isfinite(c.yaw)) return invalid("camera.yaw", "must be finite");
  if (!std::isfinite(c.pitch)) return invalid("camera.pitch", "must be finite");
  if (!(c.fov > 1.0f && c.fov < 179.0f)) return invalid("camera.fov", "must be between 1 and 179 degrees");

  const EnvironmentSettings& e = s.environment;
  if (!std::isfinite(e.intensity) || e.intensity < 0 || e.intensity > 1e6f)
    return invalid("environment.intensity", "must be between 0 and 1e6");
  if (!std::isfinite(e.rotation)) return invalid("environment.rotation", "must be finite");

  if (s.objects.size() > static_cast<size_t>(kMaxObjects)) return invalid("objects", "at most 64 objects");
  for (size_t i = 0; i < s.objects.size(); ++i) {
    const SceneObject& o = s.objects[i];
    const std::string at = "objects[" + std::to_string(i) + "]";
    if (!o.brdf) return invalid(at + ".brdf", "no BRDF given");
    if (!finite3(o.translate)) return invalid(at + ".translate", "must be finite");
    if (!finite3(o.rotate)) return invalid(at + ".rotate", "must be finite");
    if (!finite3(o.scale)) return invalid(at + ".scale", "must be finite");
    for (float v : o.scale)
      if (std::fabs(v) < 1e-6f || std::fabs(v) > 1e6f)
        return invalid(at + ".scale", "each factor must be within 1e-6..1e6 in magnitude");
    if (o.textures.size() > static_cast<size_t>(kMaxTextures)) return invalid(at + ".textures", "at most 4 textures");
    for (const auto& [name, value] : o.params) {
      const std::string field = at + ".params." + name;
      if (!o.brdf->findParam(name)) return invalid(field, "the BRDF has no parameter of this name");
      if (!finite3(value)) return invalid(field, "must be finite");
    }
  }
  return {};
}

}  // namespace brdfa
