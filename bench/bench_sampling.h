#pragma once
#include <string>
namespace brdfa::bench {
// Prints the sampling-strategy table (equal-time relMSE against cosine, samples/s);
// returns a process exit code. `sceneFilter` (if not empty) keeps the scenes whose label holds it.
int runSamplingBench(const std::string& sourceDir, int rounds, const std::string& sceneFilter = "");
}  // namespace brdfa::bench
