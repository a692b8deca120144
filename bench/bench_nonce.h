// Constants that differ on every run, so a "new BRDF" is new to every cache, Mesa's on-disk
// shader cache included (it survives between runs and would turn a JIT into a file read).
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace brdfa::bench {

// A GLSL float literal in (1, 1.001) unique to this process run and to `i`.
inline std::string uniqueFactor(int i) {
  static const long long run = std::chrono::steady_clock::now().time_since_epoch().count() % 1000000007LL;
  char text[64];
  std::snprintf(text, sizeof text, "%.12f", 1.0 + 1e-9 * static_cast<double>((run * 131 + i * 7919) % 999983 + 1));
  return text;
}

// `source` (a .brdf text) with its first `return <returned>` scaled by uniqueFactor(i): a BRDF
// new to every cache, with the same value to 1 part in 1000. Empty (a file that fails to
// parse, with its error) when `source` has no such return.
inline std::string withUniqueFactor(std::string source, const std::string& returned, int i) {
  const std::string line = "return " + returned;
  const size_t at = source.find(line);
  if (at == std::string::npos) return {};
  return source.replace(at, line.size(), "return " + uniqueFactor(i) + " * " + returned);
}

}  // namespace brdfa::bench
