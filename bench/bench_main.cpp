// brdfa-bench: prints the figures DESIGN.md section 5 asks for, as medians, in one run: the
// renderer's (library level) and the service's (through the real server over loopback HTTP).
//   brdfa-bench [--rounds N] [--source DIR] [--only renderer|scenes|sampling|split|http] [--scene TEXT]
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <string>

#include "bench_http.h"
#include "bench_renderer.h"
#include "bench_sampling.h"
#include "bench_scenes.h"
#include "bench_split.h"

int main(int argc, char** argv) {
  std::string source = BRDFA_SOURCE_DIR;
  int rounds = 15;
  std::string only, sceneFilter;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--rounds" && i + 1 < argc) rounds = std::atoi(argv[++i]);
    else if (a == "--source" && i + 1 < argc) source = argv[++i];
    else if (a == "--only" && i + 1 < argc) only = argv[++i];
    else if (a == "--scene" && i + 1 < argc) sceneFilter = argv[++i];  // sampling scenes whose label holds TEXT
    else {
      std::fprintf(stderr, "usage: brdfa-bench [--rounds N] [--source DIR] [--only renderer|scenes|sampling|split|http] [--scene TEXT]\n");
      return 2;
    }
  }
  auto wanted = [&](const char* part) { return only.empty() || only == part; };
  int code = 0;
  if (wanted("renderer") && (code = brdfa::bench::runRendererBench(source, rounds)) != 0) return code;
  if (wanted("scenes") && (code = brdfa::bench::runSceneBench(source, rounds)) != 0) return code;
  if (wanted("sampling") && (code = brdfa::bench::runSamplingBench(source, std::max(1, rounds / 5), sceneFilter)) != 0) return code;
  if (wanted("split") && (code = brdfa::bench::runSplitBench(source, rounds)) != 0) return code;
  if (wanted("http")) code = brdfa::bench::runHttpBench(BRDFA_SERVER_BINARY, source);
  return code;
}
