// JSON views of BRDFs for GET /api/brdfs and the validate/PUT replies.
#pragma once

#include <nlohmann/json.hpp>

#include "brdfa/brdf.h"
#include "storage/brdf_library.h"

namespace brdfa::server {

const char* brdfFormatName(BrdfFormat format);  // "explorer" | "legacy"

// [{name, type, min, max, default}]; default is a number (float), [r,g,b] (color) or a bool.
nlohmann::json paramsToJson(const std::vector<BrdfParam>& params);

// The value of one parameter as the scene JSON writes it (same shapes as `default`).
nlohmann::json paramValueToJson(ParamType type, const Vec3& value);

// {name, format, builtin, params}; with `withSource` also {source}.
nlohmann::json brdfEntryToJson(const BrdfEntry& entry, bool withSource);

}  // namespace brdfa::server
