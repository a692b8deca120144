#pragma once
#include <string>
namespace brdfa::bench {
// Prints the renderer-level table; returns a process exit code.
int runRendererBench(const std::string& sourceDir, int rounds);
}  // namespace brdfa::bench
