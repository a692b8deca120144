#pragma once
#include <string>
namespace brdfa::bench {
// What authentication costs per request: the same GET against a server in `none` mode and one
// in `tokens` mode (a student's bearer token), interleaved in one run; prints a table.
int runAuthBench(const std::string& serverBinary, const std::string& sourceDir, int rounds);
}  // namespace brdfa::bench
