// Measured BRDFs: reading a MERL table, uploading one to the server until it is usable, and a
// scene's first frame with it.
#pragma once

#include <string>

namespace brdfa::bench {

int runMeasuredBench(const std::string& serverBinary, const std::string& sourceDir, int rounds);

}  // namespace brdfa::bench
