// Runs the real brdfa-server binary on a loopback port (--port 0), reads its `listening on`
// line, and stops it with SIGTERM, reporting the exit status. Shared by the integration tests
// and the benchmark; no test framework inside.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <httplib.h>

namespace brdfa::testsupport {

// Forks and runs `args` (args[0]: the binary), its stdout into a pipe whose read end goes to
// `outFd`, its stderr into `logPath`, without the environment variables in `unsetEnv`. The
// child's pid, or -1 when it could not be started.
pid_t spawnLogged(std::vector<std::string> args, const std::string& logPath, int& outFd,
                  const std::vector<std::string>& unsetEnv = {});

class ServerProcess {
 public:
  ServerProcess() = default;
  ~ServerProcess();  // kills a server still running
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  // Starts `binary` --port 0 --root `root` --data-dir <fresh temp dir> plus `extraArgs`, waits
  // for the listening line and a healthy /api/health. Returns "" on success, else why it failed
  // (with the server log).
  std::string start(const std::string& binary, const std::string& root, const std::vector<std::string>& extraArgs = {});

  // SIGTERM, then waits up to `timeout` for exit. Returns the exit code; -1 if it died by a
  // signal or had to be killed after the timeout.
  int terminate(std::chrono::seconds timeout = std::chrono::seconds(30));

  bool running() const { return pid_ > 0; }
  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  std::string logTail(size_t bytes = 6000) const;  // the server's stderr
  // Resident memory of the server and of every process below it (render workers, the spare,
  // compile workers), from /proc; 0 when it is not running.
  uint64_t treeResidentBytes() const;

  std::unique_ptr<httplib::Client> client(int readTimeoutSec = 120) const;

 private:
  pid_t pid_ = -1;
  int port_ = 0;
  int stdoutFd_ = -1;
  std::string tmpDir_;
};

}  // namespace brdfa::testsupport
