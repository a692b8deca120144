// Small helpers for the benchmark table: medians and aligned rows.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace brdfa::bench {

// Milliseconds since `t0`.
inline double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// A whole text file ("" when it cannot be read).
inline std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

inline void row(const std::string& what, double value, const std::string& unit, const std::string& note = "") {
  std::printf("| %-58s | %10.2f | %-10s | %s\n", what.c_str(), value, unit.c_str(), note.c_str());
}

inline void header(const std::string& title) {
  std::printf("\n%s\n| %-58s | %10s | %-10s | %s\n", title.c_str(), "measure", "median", "unit", "note");
}

}  // namespace brdfa::bench
