#pragma once
#include <string>
namespace brdfa::bench {
// Prints what splitting passes into bounded submissions costs: a normal scene's
// throughput and first pass after a parameter change, split (RendererOptions default) against
// unsplit (submissionTargetMs 0), interleaved in one process.
int runSplitBench(const std::string& sourceDir, int rounds);
}  // namespace brdfa::bench
