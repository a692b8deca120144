// Reading request bodies at the JSON boundary: nothing nlohmann throws gets past here.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

#include "brdfa/result.h"

namespace brdfa::server {

// Body limits. httplib itself rejects anything above kMaxJsonBody with 413 before a handler
// runs; handlers taking .brdf text apply the smaller limit.
inline constexpr size_t kMaxJsonBody = 4u << 20;
inline constexpr size_t kMaxBrdfSource = 1u << 20;
// Deeper nesting than any scene needs; bounded so recursive code (dump, copy) cannot overflow
// the stack on a hostile body like 1,000,000 '['.
inline constexpr int kMaxJsonDepth = 64;

// Outcome of parsing a body: the document, or the reason ("bad_json" + message).
struct JsonBody {
  bool ok = false;
  nlohmann::json value;
  std::string message;
};

// Parses `text` as one JSON document. Rejects syntax errors, nesting deeper than
// kMaxJsonDepth and invalid UTF-8, with a message that says where.
JsonBody parseJsonBody(const std::string& text);

// Depth of the deepest [ or { in `text`, ignoring brackets inside strings.
int jsonNestingDepth(const std::string& text);

}  // namespace brdfa::server
