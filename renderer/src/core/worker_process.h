// Helper processes of the renderer (brdfa-compile-worker, brdfa-render-worker): finding their
// executables, starting them with a socket as stdin and stdout, watching and ending them.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

#include "brdfa/result.h"

#if defined(__SANITIZE_ADDRESS__)
#define BRDFA_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define BRDFA_UNDER_ASAN 1
#endif
#endif

namespace brdfa::worker_process {

// AddressSanitizer's shadow memory makes resident sizes (and address-space caps) meaningless:
// memory budgets of worker processes are not applied in such a build.
#ifdef BRDFA_UNDER_ASAN
inline constexpr bool kMemoryBudgetsApply = false;
#else
inline constexpr bool kMemoryBudgetsApply = true;
#endif
// What the shadow memory adds to a process's resident size under AddressSanitizer, where a
// memory watch still runs (the compile pool's): it makes an idle brdfa-compile-worker several
// times larger there.
inline constexpr uint64_t kSanitizerResidentBytes = kMemoryBudgetsApply ? 0 : uint64_t(256) << 20;

struct Child {
  pid_t pid = -1;
  int fd = -1;  // our end of the socket that is the child's stdin and stdout
};

// The executable `name`: $<envVar> when set to a file, else `name` beside the running
// executable, else `builtPath` (the build tree's). Empty when none exists.
std::string find(const std::string& name, const char* envVar, const char* builtPath);

// Starts `path` with `args` (argv[1..]) and a fresh socket as its stdin and stdout.
Result<Child> spawn(const std::string& path, const std::vector<std::string>& args);

// SIGKILLs and reaps the child (when running) and closes the socket; returns its wait status
// (0 when there was no child). Leaves `child` empty.
int killAndReap(Child& child);

// "signal 9" or "exit status 1", for a wait status.
std::string describeStatus(int status);

// Resident set size of `pid` in bytes, from /proc/<pid>/statm (0 when unreadable).
uint64_t residentBytes(pid_t pid);

}  // namespace brdfa::worker_process
