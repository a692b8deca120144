// brdfa-compile-worker: compiles GLSL for the renderer's CompilePool (compile_pool.h), one
// program at a time, in a process of its own under a memory limit. Reads request frames on
// stdin, writes reply frames on stdout (compile_protocol.h), exits at end of input.
#include <sys/resource.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "core/worker_process.h"
#include "programs/compile_protocol.h"
#include "programs/glsl_compiler.h"

int main(int argc, char** argv) {
  unsigned long long memoryMiB = 0;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--memory-mib") == 0) memoryMiB = std::strtoull(argv[i + 1], nullptr, 10);
#if !defined(BRDFA_UNDER_ASAN)
  // The hard cap: allocation fails past it (glslang then throws or the process dies), whatever
  // the pool's RSS watch sees. Address space, not RSS, so it is larger than the budget by what
  // the process maps without using (libraries, stacks). Under AddressSanitizer the shadow
  // memory's reservation makes any such cap fail at start; the pool's RSS watch still applies.
  if (memoryMiB > 0) {
    const rlim_t bytes = static_cast<rlim_t>(memoryMiB + 256) << 20;
    rlimit limit{bytes, bytes};
    setrlimit(RLIMIT_AS, &limit);
  }
#endif
  // The protocol owns the channel; anything a library prints goes to stderr instead.
  const int channel = dup(0);
  dup2(2, 1);
  for (;;) {
    std::string frame;
    if (!brdfa::compile_protocol::readFrame(channel, frame, 64u << 20)) return 0;
    brdfa::ShaderStage stage;
    std::string source;
    brdfa::Result<brdfa::SpirvBinary> result =
        brdfa::compile_protocol::decodeRequest(frame, stage, source)
            ? brdfa::compileGlsl(stage, source)
            : brdfa::Result<brdfa::SpirvBinary>(brdfa::makeError(brdfa::ErrorCode::Internal, "garbled request"));
    if (!brdfa::compile_protocol::writeFrame(channel, brdfa::compile_protocol::encodeReply(result))) return 0;
  }
}
