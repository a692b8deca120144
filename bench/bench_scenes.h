#pragma once
#include <string>
namespace brdfa::bench {
// Prints the scene table: per-pass cost of a 511k-triangle mesh against the
// 32k-triangle sphere at equal coverage, and what specialization buys (program size and
// first-frame time of a lambert-only scene against one with textures and anisotropy).
int runSceneBench(const std::string& sourceDir, int rounds);
}  // namespace brdfa::bench
