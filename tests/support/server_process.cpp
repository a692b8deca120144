#include "server_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

namespace brdfa::testsupport {

namespace {

using Clock = std::chrono::steady_clock;

// Reads one '\n'-terminated line from `fd` within `timeout`.
bool readLine(int fd, std::string& line, std::chrono::milliseconds timeout) {
  auto deadline = Clock::now() + timeout;
  line.clear();
  while (Clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    int left = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
    int n = ::poll(&p, 1, std::max(left, 1));
    if (n <= 0) continue;
    char c;
    ssize_t got = ::read(fd, &c, 1);
    if (got <= 0) return false;  // EOF: the server exited
    if (c == '\n') return true;
    line += c;
  }
  return false;
}

}  // namespace

ServerProcess::~ServerProcess() {
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    int status = 0;
    ::waitpid(pid_, &status, 0);
  }
  if (stdoutFd_ >= 0) ::close(stdoutFd_);
  if (!tmpDir_.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(tmpDir_, ec);
  }
}

uint64_t ServerProcess::treeResidentBytes() const {
  if (pid_ <= 0) return 0;
  // Every process's parent, then the sum over the server's descendants.
  std::map<pid_t, pid_t> parent;
  std::map<pid_t, uint64_t> resident;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = std::atoi(name.c_str());
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const size_t close = line.rfind(')');  // the command name may hold spaces and parentheses
    if (close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    char state;
    pid_t ppid = 0;
    rest >> state >> ppid;
    parent[pid] = ppid;
    std::ifstream statm(entry.path() / "statm");
    unsigned long long size = 0, pages = 0;
    if (statm >> size >> pages) resident[pid] = pages * uint64_t(sysconf(_SC_PAGESIZE));
  }
  uint64_t total = 0;
  for (const auto& [pid, bytes] : resident) {
    for (pid_t p = pid; p > 1; p = parent.count(p) ? parent[p] : 0) {
      if (p == pid_) {
        total += bytes;
        break;
      }
    }
  }
  return total;
}

std::string ServerProcess::logTail(size_t bytes) const {
  std::ifstream in(tmpDir_ + "/server.log", std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  return s.size() > bytes ? "..." + s.substr(s.size() - bytes) : s;
}

namespace {
// A test is a client of a server that may close a connection while the test still writes (a
// refused upload, a cut slow request): that is an EPIPE to check, not a signal that ends the run.
const bool kIgnoreSigpipe = [] {
  signal(SIGPIPE, SIG_IGN);
  return true;
}();
}  // namespace

pid_t spawnLogged(std::vector<std::string> args, const std::string& logPath, int& outFd,
                  const std::vector<std::string>& unsetEnv) {
  int out[2];
  if (::pipe(out) != 0) return -1;
  pid_t pid = ::fork();
  if (pid < 0) {
    ::close(out[0]);
    ::close(out[1]);
    return -1;
  }
  if (pid == 0) {
    for (const std::string& name : unsetEnv) ::unsetenv(name.c_str());
    ::dup2(out[1], STDOUT_FILENO);
    int log = ::open(logPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (log >= 0) ::dup2(log, STDERR_FILENO);
    ::close(out[0]);
    ::close(out[1]);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(out[1]);
  outFd = out[0];
  return pid;
}

std::string ServerProcess::start(const std::string& binary, const std::string& root,
                                 const std::vector<std::string>& extraArgs) {
  char tmpl[] = "/tmp/brdfa-itest-XXXXXX";
  if (!::mkdtemp(tmpl)) return "mkdtemp failed";
  tmpDir_ = tmpl;
  std::string dataDir = tmpDir_ + "/data";
  std::string logPath = tmpDir_ + "/server.log";

  std::vector<std::string> args = {binary, "--port", "0", "--root", root, "--data-dir", dataDir};
  args.insert(args.end(), extraArgs.begin(), extraArgs.end());

  int outFd = -1;
  pid_t pid = spawnLogged(std::move(args), logPath, outFd);
  if (pid < 0) return "fork failed";
  pid_ = pid;
  stdoutFd_ = outFd;

  std::string line;
  if (!readLine(stdoutFd_, line, std::chrono::seconds(60)))
    return "no `listening on` line within 60 s; server log:\n" + logTail();
  const std::string prefix = "listening on http://127.0.0.1:";
  if (line.rfind(prefix, 0) != 0) return "unexpected first line: '" + line + "'";
  port_ = std::atoi(line.c_str() + prefix.size());
  if (port_ <= 0) return "no port in: '" + line + "'";

  auto cli = client(5);
  for (auto deadline = Clock::now() + std::chrono::seconds(30); Clock::now() < deadline;) {
    auto r = cli->Get("/api/health");
    if (r && r->status == 200) return "";
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return "/api/health never answered 200; server log:\n" + logTail();
}

int ServerProcess::terminate(std::chrono::seconds timeout) {
  if (pid_ <= 0) return -1;
  ::kill(pid_, SIGTERM);
  int status = 0;
  auto deadline = Clock::now() + timeout;
  for (;;) {
    pid_t r = ::waitpid(pid_, &status, WNOHANG);
    if (r == pid_) break;
    if (Clock::now() > deadline) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
      pid_ = -1;
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  pid_ = -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::unique_ptr<httplib::Client> ServerProcess::client(int readTimeoutSec) const {
  auto cli = std::make_unique<httplib::Client>("127.0.0.1", port_);
  cli->set_connection_timeout(5);
  cli->set_read_timeout(readTimeoutSec);
  cli->set_write_timeout(30);
  return cli;
}

}  // namespace brdfa::testsupport
