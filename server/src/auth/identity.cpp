#include "auth/identity.h"

#include <algorithm>

#include "util/display_text.h"

namespace brdfa::server {

const char* roleName(Role role) { return role == Role::Teacher ? "teacher" : "student"; }

std::optional<Role> roleFromName(std::string_view name) {
  if (name == roleName(Role::Teacher)) return Role::Teacher;
  if (name == roleName(Role::Student)) return Role::Student;
  return std::nullopt;
}

Identity localIdentity() { return Identity{}; }

namespace {
bool lowerAlnum(char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'); }
}  // namespace

bool isReservedUserName(std::string_view name) {
  return name == "teacher" || name == "admin" || name == "default" || name == "course" || name == "nobody" ||
         name == "presets";  // /api/brdfs/<user>/... must never read as a BRDF's presets
}

std::string cleanDisplayName(std::string_view raw) { return cleanDisplayText(raw, 64); }

std::string userNameFromDisplayName(std::string_view displayName) {
  std::string out;
  for (char ch : displayName) {
    char c = (ch >= 'A' && ch <= 'Z') ? static_cast<char>(ch - 'A' + 'a') : ch;
    if (lowerAlnum(c)) {
      out.push_back(c);
    } else if (!out.empty() && out.back() != '-') {
      out.push_back('-');
    }
    if (out.size() >= 32) break;
  }
  while (!out.empty() && out.back() == '-') out.pop_back();
  return out.empty() ? "student" : out;
}

}  // namespace brdfa::server
