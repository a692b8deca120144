// Float <-> JSON number conversion that keeps documents readable and round-trips exactly.
#pragma once

#include <charconv>
#include <string>

namespace brdfa::server {

// The double whose shortest decimal form equals the float's shortest decimal form, so 0.3f is
// written as 0.3 (not 0.30000001192092896) and still reads back as exactly 0.3f.
inline double floatForJson(float value) {
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  if (ec != std::errc()) return static_cast<double>(value);
  double out = 0;
  auto [p, ec2] = std::from_chars(buf, end, out);
  if (ec2 != std::errc()) return static_cast<double>(value);
  return out;
}

}  // namespace brdfa::server
