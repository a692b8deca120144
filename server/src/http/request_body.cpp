#include "http/request_body.h"

namespace brdfa::server {

int jsonNestingDepth(const std::string& text) {
  int depth = 0, deepest = 0;
  bool inString = false, escaped = false;
  for (char c : text) {
    if (inString) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        inString = false;
      continue;
    }
    if (c == '"')
      inString = true;
    else if (c == '[' || c == '{')
      deepest = std::max(deepest, ++depth);
    else if (c == ']' || c == '}')
      --depth;
  }
  return deepest;
}

JsonBody parseJsonBody(const std::string& text) {
  JsonBody out;
  if (jsonNestingDepth(text) > kMaxJsonDepth) {
    out.message = "JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels";
    return out;
  }
  try {
    out.value = nlohmann::json::parse(text);
    out.ok = true;
  } catch (const nlohmann::json::exception& e) {
    out.message = std::string("request body is not valid JSON: ") + e.what();
  }
  return out;
}

}  // namespace brdfa::server
