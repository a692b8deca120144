// Scene JSON (docs/design.md section 4.1, docs/api.md Scene JSON) <-> brdfa::Scene. Every field is optional; missing
// ones take the defaults below. Validation is strict and names the offending field ("render.width",
// "objects[0].params.Kd"): wrong types, non-finite or absurd numbers and unknown keys are
// InvalidArgument (400), unknown BRDF/environment/mesh names NotFound (404).
#pragma once

#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <functional>
#include <string>
#include <vector>

#include "brdfa/result.h"
#include "brdfa/scene.h"
#include "storage/brdf_library.h"

namespace brdfa::server {

// What names in a scene can resolve to.
struct SceneResolver {
  // The BRDF a name means to this scene's requester; null (and no function) is "unknown".
  std::function<std::shared_ptr<const BrdfEntry>(std::string_view)> findBrdf;
  // The BRDF that objects named "inline" use (one-shot renders); null = "inline" is refused.
  std::shared_ptr<const BrdfDefinition> inlineBrdf;
  std::vector<std::string> environments;
  std::vector<std::string> meshes;
  std::vector<std::string> textures;
};

// Defaults for fields the JSON leaves out (the Scene struct's own defaults, plus these).
inline constexpr const char* kDefaultMesh = "sphere";
inline constexpr const char* kDefaultBrdf = "lambert";  // also the one object of a scene without "objects"
inline constexpr const char* kInlineBrdfName = "inline";
// render.sampling's names, for error messages (brdfa::samplingModeFromName accepts them).
inline constexpr const char* kSamplingChoices = "\"cosine\", \"uniform\", \"brdf\", \"environment\" or \"mis\"";

// Parses and validates. Every object's params are filled in completely (explicit value or the
// BRDF's default), so sceneToJson(sceneFromJson(j)) lists them all and parses back to an equal
// Scene. A parameter value outside its BRDF's range (a float's min..max, a color's 0..1) is
// clamped into it, and `notes` (optional) gets a line saying so: values carried over from
// another BRDF by name (Disney's roughness 0 into ggx, whose minimum is 0.001) render as the
// sliders show them, never as NaN. A top-level "notes" key is accepted and ignored, so a GET
// scene can be PUT back.
Result<Scene> sceneFromJson(const nlohmann::json& json, const SceneResolver& resolver,
                            std::vector<std::string>* notes = nullptr);

// One parameter value with the rules of `objects[i].params` (right type, finite, bools as
// true/false/0/1); errors are InvalidArgument naming `field`.
Result<Vec3> paramValueFromJson(const BrdfParam& param, const nlohmann::json& value, const std::string& field);

// A BRDF's parameter values from a JSON object of name -> value (null: none given), with the
// rules of `objects[i].params`: every parameter present (missing ones at the file's default),
// unknown names and bad values InvalidArgument naming `field`.name, values outside the range
// clamped with a note in `notes` (optional).
Result<std::map<std::string, Vec3>> paramsFromJson(const BrdfDefinition& brdf, const std::string& brdfName,
                                                   const nlohmann::json* params, const std::string& field,
                                                   std::vector<std::string>* notes = nullptr);

// The full scene with every field present, plus "notes" (what sceneFromJson clamped) when
// `notes` is not empty.
nlohmann::json sceneToJson(const Scene& scene, const std::vector<std::string>& notes = {});

}  // namespace brdfa::server
