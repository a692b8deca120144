#include "class_breakdown.h"

#include <dirent.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <sstream>
#include <vector>

#include <httplib.h>

#include "bench_util.h"

namespace brdfa::bench {

namespace {

std::string firstLine(const std::string& s) { return s.substr(0, s.find('\n')); }

// The fields after the ")" that ends the command name in /proc/.../stat (field 3 is the first).
std::vector<std::string> statFields(const std::string& path) {
  const std::string text = readText(path);
  const size_t close = text.rfind(')');
  std::vector<std::string> fields;
  if (close == std::string::npos) return fields;
  std::istringstream in(text.substr(close + 2));
  for (std::string f; in >> f;) fields.push_back(f);
  return fields;
}
// Field `n` of stat (1-based, as in proc(5)) as a number.
double statField(const std::vector<std::string>& fields, int n) {
  const size_t i = size_t(n - 3);
  return i < fields.size() ? std::atof(fields[i].c_str()) : 0.0;
}

std::vector<pid_t> numberedEntries(const std::string& dir) {
  std::vector<pid_t> out;
  if (DIR* d = ::opendir(dir.c_str())) {
    while (dirent* e = ::readdir(d))
      if (e->d_name[0] >= '0' && e->d_name[0] <= '9') out.push_back(pid_t(std::atol(e->d_name)));
    ::closedir(d);
  }
  return out;
}

// `root` and every process below it.
std::set<pid_t> processTree(pid_t root) {
  std::map<pid_t, pid_t> parent;
  for (pid_t p : numberedEntries("/proc"))
    parent[p] = pid_t(statField(statFields("/proc/" + std::to_string(p) + "/stat"), 4));
  std::set<pid_t> tree{root};
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& [p, pp] : parent)
      if (tree.count(pp) && !tree.count(p)) grew = tree.insert(p).second;
  }
  return tree;
}

double statusField(const std::string& status, const std::string& key) {
  const size_t at = status.find(key + ":");
  return at == std::string::npos ? 0.0 : std::atof(status.c_str() + at + key.size() + 1);
}

// The part of the breakdown a thread's CPU time belongs to. Lavapipe's compute threads carry
// the process's name (only its rasterizer threads are llvmpipe-N); the project's own threads
// are named (pthread_setname_np), the main thread is the process's.
std::string classify(const std::string& process, const std::string& thread, bool mainThread, bool self) {
  if (self) return "bench: stream readers (the class's browsers)";
  const bool unnamed = thread == process;
  if (process.rfind("brdfa-render-wo", 0) == 0) {
    if (mainThread) return "worker: channel reader (main thread)";
    if (thread == "worker-request") return "worker: request threads (submit, wait, read back, copy)";
    if (unnamed || thread.rfind("llvmpipe-", 0) == 0) return "worker: lavapipe threads (shading, tone mapping)";
    return "worker: watchdog and shader cache";
  }
  if (process.rfind("brdfa-server", 0) == 0) {
    if (thread == "brdfa-http") return "server: HTTP threads (requests, streams)";
    if (thread == "brdfa-render") return "server: session render loops (passes, reads)";
    if (thread == "brdfa-encode") return "server: PNG encoding";
    if (thread == "brdfa-channel") return "server: render worker channel reader";
    if (mainThread) return "server: main thread (accepts)";
    if (unnamed || thread.rfind("llvmpipe-", 0) == 0) return "server: lavapipe and other unnamed threads";
    return "server: supervisor, jobs and other named threads";
  }
  if (process.rfind("brdfa-compile", 0) == 0) return "compile workers";
  return "other processes of the server";
}

std::string processName(pid_t p) { return firstLine(readText("/proc/" + std::to_string(p) + "/comm")); }

}  // namespace

ClassSnapshot takeClassSnapshot(pid_t serverPid, int port) {
  ClassSnapshot s;
  const double hz = double(::sysconf(_SC_CLK_TCK));
  std::set<pid_t> pids = processTree(serverPid);
  const pid_t self = ::getpid();
  pids.insert(self);
  for (pid_t p : pids) {
    const std::string base = "/proc/" + std::to_string(p);
    const std::string process = processName(p);
    const std::vector<std::string> whole = statFields(base + "/stat");
    double threadsSeconds = 0;
    std::string someThreadPart;
    for (pid_t t : numberedEntries(base + "/task")) {
      const std::string task = base + "/task/" + std::to_string(t);
      const std::vector<std::string> f = statFields(task + "/stat");
      const double seconds = (statField(f, 14) + statField(f, 15)) / hz;
      const std::string part = classify(process, firstLine(readText(task + "/comm")), t == p, p == self);
      s.cpuSeconds[part] += seconds;
      threadsSeconds += seconds;
      const std::string status = readText(task + "/status");
      const std::string kind = p == self ? "bench" : process.rfind("brdfa-render-wo", 0) == 0 ? "worker" : "server";
      s.switches[kind + " voluntary"] += statusField(status, "voluntary_ctxt_switches");
      s.switches[kind + " involuntary"] += statusField(status, "nonvoluntary_ctxt_switches");
    }
    // Threads that ended (a request thread of an earlier burst) keep their time in the
    // process's; children that ended (compile workers, a replaced worker) in the parent's.
    const double processSeconds = (statField(whole, 14) + statField(whole, 15)) / hz;
    const std::string kind = p == self ? "bench" : process.rfind("brdfa-render-wo", 0) == 0 ? "worker" : "server";
    s.cpuSeconds[kind + ": threads that ended"] += std::max(0.0, processSeconds - threadsSeconds);
    if (p != self)
      s.cpuSeconds["children that ended (compile workers)"] += (statField(whole, 16) + statField(whole, 17)) / hz;
  }
  std::istringstream cpu(firstLine(readText("/proc/stat")));
  std::string label;
  cpu >> label;
  std::vector<double> ticks;
  for (double v; ticks.size() < 8 && cpu >> v;) ticks.push_back(v);
  for (double v : ticks) s.machineSeconds += v / hz;
  if (ticks.size() >= 5) s.idleSeconds = (ticks[3] + ticks[4]) / hz;

  httplib::Client cli("127.0.0.1", port);
  cli.set_read_timeout(30);
  if (auto r = cli.Get("/metrics"); r && r->status == 200) {
    std::istringstream lines(r->body);
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("brdfa_worker_", 0) != 0 && line.rfind("brdfa_samples_rendered_total", 0) != 0) continue;
      const size_t space = line.rfind(' ');
      s.metrics[line.substr(0, space)] = std::atof(line.c_str() + space + 1);
    }
  }
  return s;
}

void printClassBreakdown(const ClassSnapshot& before, const ClassSnapshot& after, double frames, double wallSeconds,
                         const std::string& title) {
  if (frames <= 0 || wallSeconds <= 0) return;
  auto delta = [](const std::map<std::string, double>& a, const std::map<std::string, double>& b,
                  const std::string& k) {
    auto x = b.find(k);
    auto y = a.find(k);
    return (x == b.end() ? 0.0 : x->second) - (y == a.end() ? 0.0 : y->second);
  };
  const double perFrame = 1000.0 / frames;  // seconds -> ms per frame
  const double machine = after.machineSeconds - before.machineSeconds;
  const double idle = after.idleSeconds - before.idleSeconds;
  header(title + ": where each frame's CPU time goes (" + std::to_string(int(frames)) + " frames in " +
         std::to_string(wallSeconds).substr(0, 4) + " s)");
  std::vector<std::pair<double, std::string>> parts;
  double ours = 0;
  double selfSeconds = 0;  // the bench's own threads
  for (const auto& [part, seconds] : after.cpuSeconds) {
    const double d = delta(before.cpuSeconds, after.cpuSeconds, part);
    if (part.rfind("bench", 0) == 0) selfSeconds += std::max(0.0, d);
    if (d <= 0.0005 * wallSeconds) continue;
    parts.emplace_back(d, part);
    ours += d;
  }
  std::sort(parts.rbegin(), parts.rend());
  auto share = [&](double seconds) {
    return std::to_string(100.0 * seconds / machine).substr(0, 4) + " % of the CPUs";
  };
  for (const auto& [seconds, part] : parts) row(part, seconds * perFrame, "core-ms", share(seconds));
  row("idle (the whole machine)", idle * perFrame, "core-ms", share(idle));
  row("the rest: other processes, the kernel's own", (machine - idle - ours) * perFrame, "core-ms",
      share(machine - idle - ours));
  // Frames are not the work: a frame of a longer pass carries more samples.
  const double samples = delta(before.metrics, after.metrics, "brdfa_samples_rendered_total");
  row("pixel samples rendered per frame delivered", samples / frames / 1e6, "million");
  if (samples > 0)
    row("CPU time of the server and workers per million samples", 1e9 * (ours - selfSeconds) / samples, "core-ms");
  row("parts measured here (threads + idle) / all CPU time", (ours + idle) / machine, "ratio",
      "within 0.9-1.1: the parts add up");
  row("all CPU time (/proc/stat) / (cores x wall time)",
      machine / (double(::sysconf(_SC_NPROCESSORS_ONLN)) * wallSeconds), "ratio",
      std::to_string(::sysconf(_SC_NPROCESSORS_ONLN)) + " cores");

  for (const char* kind : {"server", "worker", "bench"})
    row(std::string("context switches of the ") + kind + " (voluntary + involuntary)",
        (delta(before.switches, after.switches, std::string(kind) + " voluntary") +
         delta(before.switches, after.switches, std::string(kind) + " involuntary")) /
            frames,
        "per frame",
        std::to_string(delta(before.switches, after.switches, std::string(kind) + " involuntary") / frames)
                .substr(0, 5) +
            " involuntary");

  const bool worker = after.metrics.count("brdfa_worker_in_flight_max");
  if (!worker || after.metrics.size() <= 2) return;
  auto metric = [&](const std::string& k) { return delta(before.metrics, after.metrics, k); };
  for (const char* op : {"renderPass", "readFrame"}) {
    const std::string o = std::string("{op=\"") + op + "\"";
    const double n = metric("brdfa_worker_requests_total" + o + "}");
    if (n <= 0) continue;
    const double rt = metric("brdfa_worker_request_seconds_total" + o + ",part=\"round_trip\"}");
    const double queue = metric("brdfa_worker_request_seconds_total" + o + ",part=\"queue\"}");
    const double serve = metric("brdfa_worker_request_seconds_total" + o + ",part=\"serve\"}");
    const double bytes = metric("brdfa_worker_bytes_total" + o + ",direction=\"to\"}") +
                         metric("brdfa_worker_bytes_total" + o + ",direction=\"from\"}");
    row(std::string(op) + " round trips", n / frames, "per frame");
    row("  bytes through the channel", bytes / frames / 1024.0, "KiB/frame");
    row("  round trip (written -> reply read)", 1000.0 * rt / n, "ms each");
    row("    waiting for a worker thread", 1000.0 * queue / n, "ms each");
    row("    served by the worker", 1000.0 * serve / n, "ms each");
    row("    the channel: copies, socket, wake-ups", 1000.0 * (rt - queue - serve) / n, "ms each");
  }
  row("requests in flight to the worker, mean", metric("brdfa_worker_in_flight_seconds_total") / wallSeconds, "at once",
      "most: " + std::to_string(int(after.metrics.at("brdfa_worker_in_flight_max"))));
}

}  // namespace brdfa::bench
