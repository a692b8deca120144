#pragma once
#include <string>
namespace brdfa::bench {
// Prints the sampling-strategy table of issue 11 (equal-time relMSE against cosine, samples/s);
// returns a process exit code.
int runSamplingBench(const std::string& sourceDir, int rounds);
}  // namespace brdfa::bench
