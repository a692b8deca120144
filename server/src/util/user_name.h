// The one rule for user names, shared by the flag parser (--proxy-admin) and identities.
#pragma once

#include <algorithm>
#include <string_view>

namespace brdfa::server {

// User names: 1-64 of [a-z0-9._@-], starting with a letter or digit.
inline bool isValidUserName(std::string_view name) {
  auto lowerAlnum = [](char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'); };
  if (name.empty() || name.size() > 64 || !lowerAlnum(name.front())) return false;
  return std::all_of(name.begin(), name.end(),
                     [&](char c) { return lowerAlnum(c) || c == '.' || c == '_' || c == '@' || c == '-'; });
}

}  // namespace brdfa::server
