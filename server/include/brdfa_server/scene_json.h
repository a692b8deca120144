// Scene JSON (DESIGN.md section 4) <-> brdfa::Scene. Every field is optional; missing ones take
// the defaults below. Validation is strict and names the offending field ("render.width",
// "objects[0].params.Kd"): wrong types, non-finite or absurd numbers and unknown keys are
// InvalidArgument (400), unknown BRDF/environment/mesh names NotFound (404).
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "brdfa/result.h"
#include "brdfa/scene.h"
#include "brdfa_server/brdf_library.h"

namespace brdfa::server {

// What names in a scene can resolve to.
struct SceneResolver {
  const BrdfLibrary* library = nullptr;
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
// Scene.
Result<Scene> sceneFromJson(const nlohmann::json& json, const SceneResolver& resolver);

// One parameter value with the rules of `objects[i].params` (right type, finite, bools as
// true/false/0/1); errors are InvalidArgument naming `field`.
Result<Vec3> paramValueFromJson(const BrdfParam& param, const nlohmann::json& value, const std::string& field);

// The full scene with every field present.
nlohmann::json sceneToJson(const Scene& scene);

}  // namespace brdfa::server
