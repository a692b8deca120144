// GLSL compilation of user text in worker processes: a pool of
// brdfa-compile-worker processes, each compiling one program at a time under a wall-clock and a
// memory budget. A program past either budget has its worker killed (and later replaced), and
// its compile fails with a CompileError that names the budget; no other compile waits behind
// it while another worker is free. A macro bomb or a pathological program thus costs one worker
// for at most the time budget, never the server's memory or its other compiles.
#pragma once

#include <sys/types.h>

#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "brdfa/result.h"

#include "programs/glsl_compiler.h"

namespace brdfa {

struct CompileBudget {
  double seconds = 5.0;     // wall clock for one compile, the worker's start excluded
  size_t memoryMiB = 1024;  // resident memory of the worker
};

class CompilePool {
 public:
  // `workerPath`: the brdfa-compile-worker executable. `maxWorkers` >= 1 run at once. They are
  // started, and warmed up with a tiny compile (glslang's first compile in a process builds its
  // built-in symbol tables), in the background, and replaced there when one is killed:
  // a user's compile never pays for a worker's start.
  CompilePool(std::string workerPath, CompileBudget budget, size_t maxWorkers);
  ~CompilePool();
  CompilePool(const CompilePool&) = delete;
  CompilePool& operator=(const CompilePool&) = delete;

  // As compileGlsl, in a worker. Fails with CompileError ("exceeds the compile budget of ...")
  // past the budget or when the compiler dies on the program, Internal when no worker starts.
  Result<SpirvBinary> compile(ShaderStage stage, const std::string& source);

  const CompileBudget& budget() const { return budget_; }
  // The worker executable to use: $BRDFA_COMPILE_WORKER, else brdfa-compile-worker beside the
  // running executable, else the build tree's. Empty when none exists.
  static std::string findWorker();

 private:
  struct Worker {
    pid_t pid = -1;
    int fd = -1;  // the socket to the worker's stdin/stdout
  };
  Result<Worker> spawn();
  // Sends `source` to `w` and waits for its reply under the budget. On any failure but a clean
  // reply, `w` is left dead (retired) and `healthy` false.
  Result<SpirvBinary> exchange(Worker& w, ShaderStage stage, const std::string& source, bool& healthy);
  static void retire(Worker& w);  // kills and reaps
  void refill();                  // the background thread: keeps maxWorkers_ warm workers
  Result<Worker> acquire();       // an idle worker; waits for one
  void release(Worker w);         // back to idle; a retired one (pid -1) frees its slot

  const std::string workerPath_;
  const CompileBudget budget_;
  const size_t maxWorkers_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Worker> idle_;
  size_t live_ = 0;  // idle + busy + being started
  bool stopping_ = false;
  std::string startError_;  // why the last start failed; empty after one succeeds
  std::thread refiller_;
};

}  // namespace brdfa
