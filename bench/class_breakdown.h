// Where a class's time goes: CPU time per thread kind of the server's process tree (server,
// render worker, compile workers) and of the bench's own stream readers, the machine's idle
// time, context switches, and the render worker's channel counters from /metrics. Two
// snapshots, one before and one after a measured stretch, give the breakdown; its parts are
// measured separately, so their sum against cores x wall time checks the accounting.
#pragma once

#include <sys/types.h>

#include <map>
#include <string>

namespace brdfa::bench {

struct ClassSnapshot {
  std::map<std::string, double> cpuSeconds;  // by part (see classify in the .cpp)
  double idleSeconds = 0;                    // the whole machine's, from /proc/stat
  double machineSeconds = 0;                 // every CPU's time, busy or idle
  std::map<std::string, double> switches;    // context switches: "<process> voluntary|involuntary"
  std::map<std::string, double> metrics;     // brdfa_worker_* and samples rendered, "name{labels}" -> value
};

// Reads the snapshot: `serverPid`'s tree, this process, /proc/stat, and GET /metrics on `port`.
ClassSnapshot takeClassSnapshot(pid_t serverPid, int port);

// Prints the breakdown of `after` - `before` over `frames` frames delivered in `wallSeconds`.
void printClassBreakdown(const ClassSnapshot& before, const ClassSnapshot& after, double frames, double wallSeconds,
                         const std::string& title);

}  // namespace brdfa::bench
