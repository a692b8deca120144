#include "compile_pool.h"

#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "compile_protocol.h"

extern char** environ;

namespace brdfa {
namespace {

constexpr uint32_t kMaxReplyBytes = 256u << 20;  // far above any SPIR-V a budget allows

// Resident set size of `pid` in MiB, from /proc/<pid>/statm (0 when unreadable).
double residentMiB(pid_t pid) {
  std::ifstream statm("/proc/" + std::to_string(pid) + "/statm");
  unsigned long long size = 0, resident = 0;
  if (!(statm >> size >> resident)) return 0;
  return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

std::string secondsText(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%g s", s);
  return text;
}

std::string budgetText(const CompileBudget& b) { return secondsText(b.seconds) + " / " + std::to_string(b.memoryMiB) + " MiB"; }

Error budgetError(const CompileBudget& b, const std::string& why) {
  Error e = makeError(ErrorCode::CompileError, "the program exceeds the compile budget of " + budgetText(b) +
                                                   " (" + why + "): simplify its macros, loops or arrays");
  e.diagnostics.push_back(Diagnostic{0, 0, "error", e.message});
  return e;
}

}  // namespace

CompilePool::CompilePool(std::string workerPath, CompileBudget budget, size_t maxWorkers)
    : workerPath_(std::move(workerPath)), budget_(budget), maxWorkers_(std::max<size_t>(1, maxWorkers)) {
  refiller_ = std::thread([this] { refill(); });
}

CompilePool::~CompilePool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  refiller_.join();
  std::lock_guard lock(mutex_);
  for (Worker& w : idle_) retire(w);
  idle_.clear();
}

void CompilePool::refill() {
  // A compute shader that does nothing: compiling it builds glslang's tables in the worker.
  static const std::string warmUp = "#version 450\nlayout(local_size_x = 1) in;\nvoid main() {}\n";
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return stopping_ || live_ < maxWorkers_; });
    if (stopping_) return;
    ++live_;
    lock.unlock();
    std::string error;
    auto spawned = spawn();
    Worker w;
    if (spawned) {
      w = spawned.value();
      bool healthy = true;
      auto warmed = exchange(w, ShaderStage::Compute, warmUp, healthy);
      if (!warmed) error = "the compile worker failed its warm-up compile: " + warmed.error().message;
      if (!healthy) w = Worker{};
    } else {
      error = spawned.error().message;
    }
    if (!error.empty()) retire(w);
    lock.lock();
    if (error.empty()) {
      startError_.clear();
      idle_.push_back(w);
    } else {
      --live_;
      startError_ = error;
    }
    changed_.notify_all();
    // guard: a missing or broken worker executable must not spin: retry once a second.
    if (!error.empty()) changed_.wait_for(lock, std::chrono::seconds(1), [&] { return stopping_; });
  }
}

std::string CompilePool::findWorker() {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (const char* env = std::getenv("BRDFA_COMPILE_WORKER"); env && fs::is_regular_file(env, ec)) return env;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = self.parent_path() / "brdfa-compile-worker";
    if (fs::is_regular_file(beside, ec)) return beside.string();
  }
#ifdef BRDFA_COMPILE_WORKER_PATH
  if (fs::is_regular_file(BRDFA_COMPILE_WORKER_PATH, ec)) return BRDFA_COMPILE_WORKER_PATH;
#endif
  return {};
}

Result<CompilePool::Worker> CompilePool::spawn() {
  if (workerPath_.empty()) return makeError(ErrorCode::Internal, "no brdfa-compile-worker executable was found");
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
    return makeError(ErrorCode::Internal, std::string("socketpair: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  // The worker's end becomes its stdin and stdout (dup2 clears close-on-exec there).
  posix_spawn_file_actions_adddup2(&actions, sv[1], 0);
  posix_spawn_file_actions_adddup2(&actions, sv[1], 1);
  const std::string memory = std::to_string(budget_.memoryMiB);
  char* argv[] = {const_cast<char*>(workerPath_.c_str()), const_cast<char*>("--memory-mib"),
                  const_cast<char*>(memory.c_str()), nullptr};
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, workerPath_.c_str(), &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(sv[1]);
  if (rc != 0) {
    ::close(sv[0]);
    return makeError(ErrorCode::Internal, "cannot start " + workerPath_ + ": " + std::strerror(rc));
  }
  return Worker{pid, sv[0]};
}

void CompilePool::retire(Worker& w) {
  if (w.pid > 0) {
    ::kill(w.pid, SIGKILL);
    while (::waitpid(w.pid, nullptr, 0) < 0 && errno == EINTR) {
    }
  }
  if (w.fd >= 0) ::close(w.fd);
  w = Worker{};
}

Result<CompilePool::Worker> CompilePool::acquire() {
  std::unique_lock lock(mutex_);
  // A start takes well under a second; past the budget plus that, a start is failing.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(budget_.seconds + 10.0);
  while (idle_.empty()) {
    if (changed_.wait_until(lock, deadline) == std::cv_status::timeout && idle_.empty())
      return makeError(ErrorCode::Internal, "no GLSL compile worker is available" +
                                                (startError_.empty() ? std::string() : ": " + startError_));
  }
  Worker w = idle_.back();
  idle_.pop_back();
  return w;
}

void CompilePool::release(Worker w) {
  std::lock_guard lock(mutex_);
  if (w.pid > 0)
    idle_.push_back(w);
  else
    --live_;  // the refiller starts a replacement
  changed_.notify_all();
}

Result<SpirvBinary> CompilePool::compile(ShaderStage stage, const std::string& source) {
  if (workerPath_.empty()) return makeError(ErrorCode::Internal, "no brdfa-compile-worker executable was found");
  auto acquired = acquire();
  if (!acquired) return acquired.takeError();
  Worker w = acquired.value();
  bool healthy = true;
  Result<SpirvBinary> result = exchange(w, stage, source, healthy);
  release(healthy ? w : Worker{});
  return result;
}

Result<SpirvBinary> CompilePool::exchange(Worker& w, ShaderStage stage, const std::string& source, bool& healthy) {
  // Any way out but a clean reply retires the worker.
  auto fail = [&](Error e) -> Result<SpirvBinary> {
    retire(w);
    healthy = false;
    return e;
  };
  if (!compile_protocol::writeFrame(w.fd, compile_protocol::encodeRequest(stage, source)))
    return fail(makeError(ErrorCode::Internal, "the compile worker did not take the program"));

  // Wait for the reply, watching the clock and the worker's memory.
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    pollfd p{w.fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, 10);
    if (ready > 0) break;
    if (ready < 0 && errno != EINTR) return fail(makeError(ErrorCode::Internal, "poll on the compile worker failed"));
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (elapsed > budget_.seconds) return fail(budgetError(budget_, "still compiling after " + secondsText(budget_.seconds)));
    if (residentMiB(w.pid) > double(budget_.memoryMiB))
      return fail(budgetError(budget_, "more than " + std::to_string(budget_.memoryMiB) + " MiB in use"));
  }
  std::string frame;
  if (!compile_protocol::readFrame(w.fd, frame, kMaxReplyBytes)) {
    // The worker died: its own memory limit (setrlimit) or a crash of the compiler.
    int status = 0;
    ::kill(w.pid, SIGKILL);
    while (::waitpid(w.pid, &status, 0) < 0 && errno == EINTR) {
    }
    w.pid = -1;
    const std::string how = WIFSIGNALED(status) ? "the compiler died with signal " + std::to_string(WTERMSIG(status))
                                                : "the compiler exited with status " + std::to_string(WEXITSTATUS(status));
    return fail(budgetError(budget_, how));
  }
  auto reply = compile_protocol::decodeReply(frame);
  if (!reply) return fail(makeError(ErrorCode::Internal, "the compile worker sent a garbled reply"));
  // The worker's address-space cap makes glslang's allocations fail: compileGlsl reports the
  // std::bad_alloc it caught. The worker may be left in any state: replace it.
  if (!reply->ok() && reply->error().message.find("bad_alloc") != std::string::npos)
    return fail(budgetError(budget_, "out of memory"));
  return std::move(*reply);
}

}  // namespace brdfa
