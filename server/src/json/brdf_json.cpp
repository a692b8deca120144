#include "json/brdf_json.h"

#include "json/json_numbers.h"

namespace brdfa::server {

const char* brdfFormatName(BrdfFormat format) { return format == BrdfFormat::Legacy ? "legacy" : "explorer"; }

nlohmann::json paramValueToJson(ParamType type, const Vec3& value) {
  switch (type) {
    case ParamType::Float: return floatForJson(value[0]);
    case ParamType::Bool: return value[0] != 0.0f;
    case ParamType::Color:
      return nlohmann::json::array({floatForJson(value[0]), floatForJson(value[1]), floatForJson(value[2])});
  }
  return nullptr;
}

nlohmann::json paramsToJson(const std::vector<BrdfParam>& params) {
  nlohmann::json out = nlohmann::json::array();
  for (const BrdfParam& p : params) {
    // Colours and bools have fixed ranges in the format; report them so a UI needs no cases.
    float lo = p.type == ParamType::Float ? p.min : 0.0f;
    float hi = p.type == ParamType::Float ? p.max : 1.0f;
    out.push_back({{"name", p.name},
                   {"type", paramTypeName(p.type)},
                   {"min", floatForJson(lo)},
                   {"max", floatForJson(hi)},
                   {"default", paramValueToJson(p.type, p.defaultValue)}});
  }
  return out;
}

nlohmann::json brdfEntryToJson(const BrdfEntry& entry, bool withSource) {
  nlohmann::json out{{"name", entry.name},
                     {"format", brdfFormatName(entry.definition->format)},
                     {"builtin", entry.builtin},
                     // Whose it is (null: a built-in or the course's) and whether classmates read it.
                     {"owner", entry.owner.empty() ? nlohmann::json(nullptr) : nlohmann::json(entry.owner)},
                     {"shared", entry.shared},
                     {"params", paramsToJson(entry.definition->params)}};
  // What the file claims (its `# claims:` line), checked by the batch test; null: no line.
  const BrdfClaims& c = entry.definition->claims;
  if (c.declared) {
    nlohmann::json claims = nlohmann::json::array();
    if (c.reciprocity) claims.push_back("reciprocity");
    if (c.energyConservation) claims.push_back("energy-conservation");
    if (c.nonNegativity) claims.push_back("non-negativity");
    out["claims"] = claims;
  } else {
    out["claims"] = nullptr;
  }
  if (withSource) out["source"] = entry.source;
  return out;
}

}  // namespace brdfa::server
