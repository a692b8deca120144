#pragma once
#include <string>

#include "brdfa/scene.h"

namespace brdfa::bench {
// The benchmark scene: the GGX sphere in the sky at 512x512, cosine sampling (the reference
// kernel's estimator), `samplesPerPass` samples a pass.
Scene ggxScene(const std::string& sourceDir, bool visibleBackground, int samplesPerPass);

// Prints the renderer-level table; returns a process exit code.
int runRendererBench(const std::string& sourceDir, int rounds);
}  // namespace brdfa::bench
