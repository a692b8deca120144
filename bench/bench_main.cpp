// brdfa-bench: prints the figures docs/design.md section 9 asks for, as medians, in one run: the
// renderer's (library level) and the service's (through the real server over loopback HTTP).
//   brdfa-bench [--rounds N] [--source DIR] [--only renderer|scenes|sampling|split|http|class|auth|measured] [--scene
//   TEXT] brdfa-bench --only shaders --against DIR[,DIR...]   (shader work: DIR/shaders against --source's,
//   interleaved)
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <string>
#include <vector>

#include "bench_auth.h"
#include "bench_http.h"
#include "bench_measured.h"
#include "bench_renderer.h"
#include "bench_sampling.h"
#include "bench_scenes.h"
#include "bench_shader_ab.h"
#include "bench_split.h"

int main(int argc, char** argv) {
  std::string source = BRDFA_SOURCE_DIR;
  int rounds = 15;
  std::string only, sceneFilter, against;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--rounds" && i + 1 < argc)
      rounds = std::atoi(argv[++i]);
    else if (a == "--source" && i + 1 < argc)
      source = argv[++i];
    else if (a == "--only" && i + 1 < argc)
      only = argv[++i];
    else if (a == "--scene" && i + 1 < argc)
      sceneFilter = argv[++i];  // sampling scenes whose label holds TEXT
    else if (a == "--against" && i + 1 < argc)
      against = argv[++i];
    else {
      std::fprintf(stderr,
                   "usage: brdfa-bench [--rounds N] [--source DIR] [--only "
                   "renderer|scenes|sampling|split|http|class|auth|measured] "
                   "[--scene TEXT] [--only shaders --against DIR[,DIR...]]\n");
      return 2;
    }
  }
  if (only == "shaders") {
    std::vector<std::string> dirs;
    for (size_t at = 0; at <= against.size();) {
      size_t comma = std::min(against.find(',', at), against.size());
      if (comma > at) dirs.push_back(against.substr(at, comma - at));
      at = comma + 1;
    }
    return brdfa::bench::runShaderAbBench(source, dirs, rounds);
  }
  auto wanted = [&](const char* part) { return only.empty() || only == part; };
  int code = 0;
  if (wanted("renderer") && (code = brdfa::bench::runRendererBench(source, rounds)) != 0) return code;
  if (wanted("scenes") && (code = brdfa::bench::runSceneBench(source, rounds)) != 0) return code;
  if (wanted("sampling") && (code = brdfa::bench::runSamplingBench(source, std::max(1, rounds / 5), sceneFilter)) != 0)
    return code;
  if (wanted("split") && (code = brdfa::bench::runSplitBench(source, rounds)) != 0) return code;
  if (wanted("http") && (code = brdfa::bench::runHttpBench(BRDFA_SERVER_BINARY, source)) != 0) return code;
  if (only == "class" && (code = brdfa::bench::runClassBench(BRDFA_SERVER_BINARY, source)) != 0) return code;
  if (wanted("auth") && (code = brdfa::bench::runAuthBench(BRDFA_SERVER_BINARY, source, std::max(5, rounds))) != 0)
    return code;
  if (wanted("measured")) code = brdfa::bench::runMeasuredBench(BRDFA_SERVER_BINARY, source, rounds);
  return code;
}
