#pragma once
#include <string>
namespace brdfa::bench {
// Prints the service-level table (through the real server over loopback HTTP); returns an exit code.
int runHttpBench(const std::string& serverBinary, const std::string& sourceDir);
}  // namespace brdfa::bench
