#pragma once
#include <string>
#include <vector>
namespace brdfa::bench {
// Pass times of the shader trees under sourceDir and each of againstDirs, interleaved in one
// run; returns a process exit code.
int runShaderAbBench(const std::string& sourceDir, const std::vector<std::string>& againstDirs, int rounds);
}  // namespace brdfa::bench
