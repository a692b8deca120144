#pragma once
#include <string>
namespace brdfa::bench {
// Prints the service-level table (through the real server over loopback HTTP), then the class
// table (runClassBench); returns an exit code.
int runHttpBench(const std::string& serverBinary, const std::string& sourceDir);
// A class of 30 sessions streaming at once, with the render worker and --in-process, and where
// each frame's time goes.
int runClassBench(const std::string& serverBinary, const std::string& sourceDir);
}  // namespace brdfa::bench
