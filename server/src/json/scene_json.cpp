#include "json/scene_json.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "json/brdf_json.h"
#include "json/json_numbers.h"

namespace brdfa::server {

namespace {

using nlohmann::json;

// Largest magnitude accepted for any free-form number (positions, angles, parameters): far
// beyond any sensible scene, small enough that float maths on it stays finite.
constexpr double kAbsurd = 1e6;

Error invalid(const std::string& field, const std::string& message) {
  return makeError(ErrorCode::InvalidArgument, field + ": " + message, field);
}

const char* typeName(const json& v) {
  // nlohmann's type_name says "number" for all numbers, which is what a JSON user expects.
  return v.type_name();
}

Result<void> checkObject(const json& v, const std::string& field) {
  if (!v.is_object())
    return invalid(field.empty() ? "scene" : field, std::string("expected an object, got ") + typeName(v));
  return {};
}

// Unknown keys are errors so that typos ("widht") do not silently fall back to defaults.
Result<void> checkKeys(const json& obj, const std::string& prefix, std::initializer_list<const char*> allowed) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    bool known = std::any_of(allowed.begin(), allowed.end(), [&](const char* k) { return it.key() == k; });
    if (!known) {
      std::string field = prefix.empty() ? it.key() : prefix + "." + it.key();
      std::string list;
      for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
      return invalid(field, "unknown key (allowed: " + list + ")");
    }
  }
  return {};
}

Result<double> readNumber(const json& v, const std::string& field, double lo, double hi) {
  if (!v.is_number()) return invalid(field, std::string("expected a number, got ") + typeName(v));
  double d = v.get<double>();
  if (!std::isfinite(d)) return invalid(field, "must be finite");
  if (d < lo || d > hi)
    return invalid(field, "must be in [" + json(lo).dump() + ", " + json(hi).dump() + "], got " + json(d).dump());
  return d;
}

Result<float> readFloat(const json& v, const std::string& field, double lo, double hi) {
  BRDFA_TRY_ASSIGN(double d, readNumber(v, field, lo, hi));
  return static_cast<float>(d);
}

// Integers may be written 64 or 64.0 (some clients only have doubles), never 64.5.
Result<int> readInt(const json& v, const std::string& field, long long lo, long long hi) {
  if (!v.is_number()) return invalid(field, std::string("expected an integer, got ") + typeName(v));
  long long n = 0;
  if (v.is_number_unsigned()) {
    auto u = v.get<unsigned long long>();
    if (u > static_cast<unsigned long long>(hi))
      return invalid(field, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    n = static_cast<long long>(u);
  } else if (v.is_number_integer()) {
    n = v.get<long long>();
  } else {
    double d = v.get<double>();
    if (!std::isfinite(d) || d != std::floor(d)) return invalid(field, "expected an integer, got " + v.dump());
    if (d < static_cast<double>(lo) || d > static_cast<double>(hi))
      return invalid(field, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    n = static_cast<long long>(d);
  }
  if (n < lo || n > hi)
    return invalid(field,
                   "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + std::to_string(n));
  return static_cast<int>(n);
}

Result<bool> readBool(const json& v, const std::string& field) {
  if (!v.is_boolean()) return invalid(field, std::string("expected true or false, got ") + typeName(v));
  return v.get<bool>();
}

Result<std::string> readString(const json& v, const std::string& field) {
  if (!v.is_string()) return invalid(field, std::string("expected a string, got ") + typeName(v));
  return v.get<std::string>();
}

Result<Vec3> readVec3(const json& v, const std::string& field, double lo, double hi) {
  if (!v.is_array() || v.size() != 3) return invalid(field, "expected an array of 3 numbers");
  Vec3 out{};
  for (size_t i = 0; i < 3; ++i) {
    BRDFA_TRY_ASSIGN(float f, readFloat(v[i], field + "[" + std::to_string(i) + "]", lo, hi));
    out[i] = f;
  }
  return out;
}

json vec3ToJson(const Vec3& v) { return json::array({floatForJson(v[0]), floatForJson(v[1]), floatForJson(v[2])}); }

// Applies `read` to obj[key] when present and stores into `dst`.
template <class T, class F>
Result<void> optionalField(const json& obj, const char* key, const std::string& prefix, T& dst, F read) {
  auto it = obj.find(key);
  if (it == obj.end()) return {};
  BRDFA_TRY_ASSIGN(auto r, read(*it, prefix + "." + key));
  dst = std::move(r);
  return {};
}

Result<void> parseCamera(const json& j, Camera& cam) {
  BRDFA_TRY(checkObject(j, "camera"));
  BRDFA_TRY(checkKeys(j, "camera", {"position", "yaw", "pitch", "fov"}));
  BRDFA_TRY(optionalField(j, "position", "camera", cam.position,
                          [](const json& v, const std::string& f) { return readVec3(v, f, -kAbsurd, kAbsurd); }));
  BRDFA_TRY(optionalField(j, "yaw", "camera", cam.yaw,
                          [](const json& v, const std::string& f) { return readFloat(v, f, -kAbsurd, kAbsurd); }));
  BRDFA_TRY(optionalField(j, "pitch", "camera", cam.pitch,
                          [](const json& v, const std::string& f) { return readFloat(v, f, -kAbsurd, kAbsurd); }));
  // Clamped, not refused: mouse-look overshoots, and at +-90 degrees the view's up vector is
  // undefined. The scene then reports the pitch it renders with.
  cam.pitch = std::clamp(cam.pitch, -kMaxPitch, kMaxPitch);
  if (auto it = j.find("fov"); it != j.end()) {
    // Open interval: 0 and 180 degrees make a degenerate projection.
    BRDFA_TRY_ASSIGN(float fov, readFloat(*it, "camera.fov", 1, 179));
    if (fov <= 1.0f || fov >= 179.0f) return invalid("camera.fov", "must be in (1, 179)");
    cam.fov = fov;
  }
  return {};
}

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// The names for an error message; with hundreds of uploads, the first 24 and a count.
std::string joinNames(const std::vector<std::string>& names) {
  constexpr size_t kListed = 24;
  std::string out;
  for (size_t i = 0; i < names.size() && i < kListed; ++i) out += (out.empty() ? "" : ", ") + names[i];
  if (names.size() > kListed) out += ", and " + std::to_string(names.size() - kListed) + " more (GET /api/assets)";
  return out;
}

Result<void> parseEnvironment(const json& j, EnvironmentSettings& env) {
  BRDFA_TRY(checkObject(j, "environment"));
  BRDFA_TRY(checkKeys(j, "environment", {"name", "intensity", "rotation", "visible"}));
  BRDFA_TRY(optionalField(j, "name", "environment", env.name, readString));
  BRDFA_TRY(optionalField(j, "intensity", "environment", env.intensity,
                          [](const json& v, const std::string& f) { return readFloat(v, f, 0, kAbsurd); }));
  BRDFA_TRY(optionalField(j, "rotation", "environment", env.rotation,
                          [](const json& v, const std::string& f) { return readFloat(v, f, -kAbsurd, kAbsurd); }));
  BRDFA_TRY(optionalField(j, "visible", "environment", env.visible, readBool));
  return {};
}

Result<void> checkEnvironmentName(const EnvironmentSettings& env, const SceneResolver& r) {
  if (!contains(r.environments, env.name))
    return makeError(
        ErrorCode::NotFound,
        "environment.name: unknown environment '" + env.name + "' (known: " + joinNames(r.environments) + ")",
        "environment.name");
  return {};
}

Result<Vec3> readParamValue(const BrdfParam& p, const json& v, const std::string& field) {
  switch (p.type) {
    case ParamType::Float: {
      BRDFA_TRY_ASSIGN(float f, readFloat(v, field, -kAbsurd, kAbsurd));
      return Vec3{f, 0, 0};
    }
    case ParamType::Color: {
      if (!v.is_array() || v.size() != 3) return invalid(field, "a color is an array of 3 numbers");
      return readVec3(v, field, -kAbsurd, kAbsurd);
    }
    case ParamType::Bool: {
      // true/false, or 0/1 as the .brdf format itself writes bools.
      if (v.is_boolean()) return Vec3{v.get<bool>() ? 1.0f : 0.0f, 0, 0};
      if (v.is_number()) {
        double d = v.get<double>();
        if (d == 0.0 || d == 1.0) return Vec3{static_cast<float>(d), 0, 0};
      }
      return invalid(field, "a bool is true, false, 0 or 1");
    }
  }
  return invalid(field, "unsupported parameter type");
}

// "textures": up to four entries, each a name ("checker") or {"name": .., "srgb": true|false}.
Result<std::vector<TextureBinding>> readTextures(const json& j, const std::string& field) {
  if (!j.is_array()) return invalid(field, std::string("expected an array, got ") + typeName(j));
  if (j.size() > static_cast<size_t>(kMaxTextures)) return invalid(field, "at most 4 textures (iTexture0..3)");
  std::vector<TextureBinding> out;
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string at = field + "[" + std::to_string(i) + "]";
    TextureBinding t;
    if (j[i].is_string()) {
      t.name = j[i].get<std::string>();
    } else {
      BRDFA_TRY(checkObject(j[i], at));
      BRDFA_TRY(checkKeys(j[i], at, {"name", "srgb"}));
      auto name = j[i].find("name");
      if (name == j[i].end()) return invalid(at + ".name", "required");
      BRDFA_TRY_ASSIGN(std::string n, readString(*name, at + ".name"));
      t.name = n;
      BRDFA_TRY(optionalField(j[i], "srgb", at, t.srgb, readBool));
    }
    out.push_back(std::move(t));
  }
  return out;
}

// `value` of parameter `p` clamped into its range; `note` says what changed (empty if nothing).
Vec3 clampParam(const BrdfParam& p, Vec3 value, const std::string& field, const std::string& brdfName,
                std::string& note) {
  auto text = [](float v) {
    char s[32];
    std::snprintf(s, sizeof s, "%g", v);
    return std::string(s);
  };
  const float lo = p.type == ParamType::Float ? p.min : 0.0f, hi = p.type == ParamType::Float ? p.max : 1.0f;
  const int n = p.type == ParamType::Color ? 3 : p.type == ParamType::Float ? 1 : 0;
  Vec3 clamped = value;
  std::string was, now;
  for (int c = 0; c < n; ++c) {
    clamped[c] = std::min(std::max(value[c], lo), hi);
    was += (c ? ", " : "") + text(value[c]);
    now += (c ? ", " : "") + text(clamped[c]);
  }
  if (clamped == value) return value;
  if (n == 3) was = "[" + was + "]", now = "[" + now + "]";
  note =
      field + ": " + was + " is outside " + brdfName + "'s range " + text(lo) + ".." + text(hi) + "; clamped to " + now;
  return clamped;
}

Result<SceneObject> parseObject(const json& j, const std::string& prefix, const SceneResolver& r,
                                std::vector<std::string>* notes) {
  SceneObject obj;
  BRDFA_TRY(checkObject(j, prefix));
  BRDFA_TRY(checkKeys(j, prefix, {"mesh", "brdf", "params", "translate", "rotate", "scale", "textures"}));
  BRDFA_TRY(optionalField(j, "mesh", prefix, obj.mesh, readString));
  std::string brdfName = kDefaultBrdf;
  BRDFA_TRY(optionalField(j, "brdf", prefix, brdfName, readString));
  BRDFA_TRY(optionalField(j, "translate", prefix, obj.translate,
                          [](const json& v, const std::string& f) { return readVec3(v, f, -kAbsurd, kAbsurd); }));
  BRDFA_TRY(optionalField(j, "rotate", prefix, obj.rotate,
                          [](const json& v, const std::string& f) { return readVec3(v, f, -kAbsurd, kAbsurd); }));
  // Positive only: a zero scale is degenerate and a negative one mirrors the mesh (flipped
  // winding and normals), which nothing here needs.
  BRDFA_TRY(optionalField(j, "scale", prefix, obj.scale,
                          [](const json& v, const std::string& f) { return readVec3(v, f, 1e-6, kAbsurd); }));
  if (auto it = j.find("textures"); it != j.end()) {
    BRDFA_TRY_ASSIGN(std::vector<TextureBinding> textures, readTextures(*it, prefix + ".textures"));
    obj.textures = std::move(textures);
  }
  // Type problems are reported before unknown names, so one request gets the 400 first.
  const json* params = nullptr;
  if (auto it = j.find("params"); it != j.end()) {
    BRDFA_TRY(checkObject(*it, prefix + ".params"));
    params = &*it;
  }

  for (size_t t = 0; t < obj.textures.size(); ++t)
    if (!contains(r.textures, obj.textures[t].name))
      return makeError(ErrorCode::NotFound,
                       prefix + ".textures[" + std::to_string(t) + "]: unknown texture '" + obj.textures[t].name +
                           "' (known: " + joinNames(r.textures) + ")",
                       prefix + ".textures[" + std::to_string(t) + "]");
  if (!contains(r.meshes, obj.mesh))
    return makeError(ErrorCode::NotFound,
                     prefix + ".mesh: unknown mesh '" + obj.mesh + "' (known: " + joinNames(r.meshes) + ")",
                     prefix + ".mesh");
  if (brdfName == kInlineBrdfName) {
    if (!r.inlineBrdf)
      return invalid(prefix + ".brdf",
                     "\"inline\" is only valid in a one-shot POST /api/render that carries brdf_source");
    obj.brdf = r.inlineBrdf;
  } else {
    auto entry = r.findBrdf ? r.findBrdf(brdfName) : nullptr;
    if (!entry)
      return makeError(ErrorCode::NotFound, prefix + ".brdf: unknown BRDF '" + brdfName + "'", prefix + ".brdf");
    obj.brdf = entry->definition;
  }
  obj.brdfName = brdfName;

  Result<std::map<std::string, Vec3>> values = paramsFromJson(*obj.brdf, brdfName, params, prefix + ".params", notes);
  if (!values) return values.takeError();
  obj.params = std::move(values.value());
  return obj;
}

Result<void> parseRender(const json& j, RenderSettings& rs) {
  BRDFA_TRY(checkObject(j, "render"));
  BRDFA_TRY(checkKeys(j, "render",
                      {"width", "height", "samples_per_frame", "max_samples", "sampling", "target_error", "seed",
                       "exposure", "tonemap"}));
  auto intIn = [](long long lo, long long hi) {
    return [lo, hi](const json& v, const std::string& f) { return readInt(v, f, lo, hi); };
  };
  BRDFA_TRY(optionalField(j, "width", "render", rs.width, intIn(kMinImageSize, kMaxImageSize)));
  BRDFA_TRY(optionalField(j, "height", "render", rs.height, intIn(kMinImageSize, kMaxImageSize)));
  BRDFA_TRY(optionalField(j, "samples_per_frame", "render", rs.samplesPerFrame, intIn(1, kMaxSamplesPerFrame)));
  BRDFA_TRY(optionalField(j, "max_samples", "render", rs.maxSamples, intIn(1, kMaxTotalSamples)));
  if (auto it = j.find("sampling"); it != j.end()) {
    BRDFA_TRY_ASSIGN(std::string s, readString(*it, "render.sampling"));
    if (!samplingModeFromName(s, rs.sampling))
      return invalid("render.sampling", std::string("must be ") + kSamplingChoices + ", got \"" + s + "\"");
  }
  // A relative RMS error to stop at: a number in (0, 1), or null (none; the default).
  if (auto it = j.find("target_error"); it != j.end() && !it->is_null()) {
    if (!it->is_number())
      return invalid("render.target_error", std::string("expected a number in (0, 1) or null, got ") + typeName(*it));
    const double t = it->get<double>();
    if (!std::isfinite(t) || t <= 0 || t >= 1)
      return invalid("render.target_error", "must be in (0, 1) or null, got " + it->dump());
    rs.targetError = t;
  }
  // Independent replicates of one scene (renderer scene.h): an integer in [0, 2^31).
  if (auto it = j.find("seed"); it != j.end()) {
    BRDFA_TRY_ASSIGN(int seed, readInt(*it, "render.seed", 0, 2147483647LL));
    rs.seed = static_cast<uint32_t>(seed);
  }
  BRDFA_TRY(optionalField(j, "exposure", "render", rs.exposure,
                          [](const json& v, const std::string& f) { return readFloat(v, f, -40, 40); }));
  if (auto it = j.find("tonemap"); it != j.end()) {
    BRDFA_TRY_ASSIGN(std::string s, readString(*it, "render.tonemap"));
    if (!toneMapFromName(s, rs.toneMap))
      return invalid("render.tonemap", "must be \"clamp\", \"reinhard\" or \"aces\", got \"" + s + "\"");
  }
  return {};
}

}  // namespace

Result<Vec3> paramValueFromJson(const BrdfParam& param, const json& value, const std::string& field) {
  return readParamValue(param, value, field);
}

Result<Scene> sceneFromJson(const json& j, const SceneResolver& r, std::vector<std::string>* notes) {
  Scene scene;
  if (!j.is_object()) return invalid("scene", std::string("a scene is a JSON object, got ") + typeName(j));
  BRDFA_TRY(checkKeys(j, "", {"camera", "environment", "objects", "render", "notes"}));
  // Shapes and ranges of every section first, then names: a request with a typo and an unknown
  // name gets the 400 for the typo.
  if (auto it = j.find("camera"); it != j.end()) BRDFA_TRY(parseCamera(*it, scene.camera));
  if (auto it = j.find("environment"); it != j.end()) BRDFA_TRY(parseEnvironment(*it, scene.environment));
  if (auto it = j.find("render"); it != j.end()) BRDFA_TRY(parseRender(*it, scene.render));
  BRDFA_TRY(checkEnvironmentName(scene.environment, r));

  if (auto it = j.find("objects"); it != j.end()) {
    if (!it->is_array()) return invalid("objects", std::string("expected an array, got ") + typeName(*it));
    if (it->size() > static_cast<size_t>(kMaxObjects))
      return invalid("objects", "at most " + std::to_string(kMaxObjects) + " objects");
    for (size_t i = 0; i < it->size(); ++i) {
      BRDFA_TRY_ASSIGN(SceneObject obj, parseObject((*it)[i], "objects[" + std::to_string(i) + "]", r, notes));
      scene.objects.push_back(std::move(obj));
    }
  } else {
    BRDFA_TRY_ASSIGN(SceneObject obj, parseObject(json::object(), "objects[0]", r, notes));
    scene.objects.push_back(std::move(obj));
  }
  return scene;
}

json sceneToJson(const Scene& s, const std::vector<std::string>& notes) {
  json objects = json::array();
  for (const SceneObject& o : s.objects) {
    json params = json::object();
    if (o.brdf) {
      for (const BrdfParam& p : o.brdf->params) {
        auto it = o.params.find(p.name);
        params[p.name] = paramValueToJson(p.type, it == o.params.end() ? p.defaultValue : it->second);
      }
    }
    json textures = json::array();
    for (const TextureBinding& t : o.textures) textures.push_back({{"name", t.name}, {"srgb", t.srgb}});
    objects.push_back({{"mesh", o.mesh},
                       {"brdf", o.brdfName},
                       {"params", params},
                       {"translate", vec3ToJson(o.translate)},
                       {"rotate", vec3ToJson(o.rotate)},
                       {"scale", vec3ToJson(o.scale)},
                       {"textures", textures}});
  }
  json out = json{
      {"camera",
       {{"position", vec3ToJson(s.camera.position)},
        {"yaw", floatForJson(s.camera.yaw)},
        {"pitch", floatForJson(s.camera.pitch)},
        {"fov", floatForJson(s.camera.fov)}}},
      {"environment",
       {{"name", s.environment.name},
        {"intensity", floatForJson(s.environment.intensity)},
        {"rotation", floatForJson(s.environment.rotation)},
        {"visible", s.environment.visible}}},
      {"objects", objects},
      {"render",
       {{"width", s.render.width},
        {"height", s.render.height},
        {"samples_per_frame", s.render.samplesPerFrame},
        {"max_samples", s.render.maxSamples},
        {"sampling", samplingModeName(s.render.sampling)},
        {"target_error", s.render.targetError > 0 ? json(s.render.targetError) : json(nullptr)},
        {"seed", s.render.seed},
        {"exposure", floatForJson(s.render.exposure)},
        {"tonemap", toneMapName(s.render.toneMap)}}},
  };
  if (!notes.empty()) out["notes"] = notes;
  return out;
}

Result<std::map<std::string, Vec3>> paramsFromJson(const BrdfDefinition& brdf, const std::string& brdfName,
                                                   const json* params, const std::string& field,
                                                   std::vector<std::string>* notes) {
  std::map<std::string, Vec3> out;
  for (const BrdfParam& p : brdf.params) out[p.name] = p.defaultValue;
  if (!params) return out;
  BRDFA_TRY(checkObject(*params, field));
  for (auto it = params->begin(); it != params->end(); ++it) {
    std::string at = field + "." + it.key();
    const BrdfParam* p = brdf.findParam(it.key());
    if (!p) {
      std::string known;
      for (const BrdfParam& q : brdf.params) known += (known.empty() ? "" : ", ") + q.name;
      return invalid(at, "BRDF '" + brdfName + "' has no parameter '" + it.key() + "' (it has: " + known + ")");
    }
    BRDFA_TRY_ASSIGN(Vec3 value, readParamValue(*p, it.value(), at));
    std::string note;
    out[p->name] = clampParam(*p, value, at, brdfName, note);
    if (!note.empty() && notes) notes->push_back(std::move(note));
  }
  return out;
}

}  // namespace brdfa::server
