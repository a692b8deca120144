#include "programs/compile_pool.h"

#include <poll.h>

#include <cerrno>
#include <chrono>
#include <cstdio>

#include "core/worker_process.h"
#include "programs/compile_protocol.h"

namespace brdfa {
namespace {

constexpr uint32_t kMaxReplyBytes = 256u << 20;  // far above any SPIR-V a budget allows

std::string secondsText(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%g s", s);
  return text;
}

std::string budgetText(const CompileBudget& b) {
  return secondsText(b.seconds) + " / " + std::to_string(b.memoryMiB) + " MiB";
}

Error budgetError(const CompileBudget& b, const std::string& why) {
  Error e = makeError(ErrorCode::CompileError, "the program exceeds the compile budget of " + budgetText(b) + " (" +
                                                   why + "): simplify its macros, loops or arrays");
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
#ifdef BRDFA_COMPILE_WORKER_PATH
  return worker_process::find("brdfa-compile-worker", "BRDFA_COMPILE_WORKER", BRDFA_COMPILE_WORKER_PATH);
#else
  return worker_process::find("brdfa-compile-worker", "BRDFA_COMPILE_WORKER", nullptr);
#endif
}

Result<CompilePool::Worker> CompilePool::spawn() {
  auto child = worker_process::spawn(workerPath_, {"--memory-mib", std::to_string(budget_.memoryMiB)});
  if (!child) return child.takeError();
  return Worker{child->pid, child->fd};
}

void CompilePool::retire(Worker& w) {
  worker_process::Child child{w.pid, w.fd};
  worker_process::killAndReap(child);
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
    if (elapsed > budget_.seconds)
      return fail(budgetError(budget_, "still compiling after " + secondsText(budget_.seconds)));
    if (worker_process::residentBytes(w.pid) >
        (uint64_t(budget_.memoryMiB) << 20) + worker_process::kSanitizerResidentBytes)
      return fail(budgetError(budget_, "more than " + std::to_string(budget_.memoryMiB) + " MiB in use"));
  }
  std::string frame;
  if (!compile_protocol::readFrame(w.fd, frame, kMaxReplyBytes)) {
    // The worker died: its own memory limit (setrlimit) or a crash of the compiler.
    worker_process::Child child{w.pid, -1};  // the socket is closed with the rest below
    const int status = worker_process::killAndReap(child);
    w.pid = -1;
    return fail(budgetError(budget_, "the compiler ended with " + worker_process::describeStatus(status)));
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
