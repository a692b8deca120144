#include "core/worker_process.h"

#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

extern char** environ;

namespace brdfa::worker_process {

std::string find(const std::string& name, const char* envVar, const char* builtPath) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (const char* env = std::getenv(envVar); env && fs::is_regular_file(env, ec)) return env;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = self.parent_path() / name;
    if (fs::is_regular_file(beside, ec)) return beside.string();
  }
  if (builtPath && fs::is_regular_file(builtPath, ec)) return builtPath;
  return {};
}

Result<Child> spawn(const std::string& path, const std::vector<std::string>& args) {
  if (path.empty()) return makeError(ErrorCode::Internal, "no worker executable was found");
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
    return makeError(ErrorCode::Internal, std::string("socketpair: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  // The child's end becomes its stdin and stdout (dup2 clears close-on-exec there).
  posix_spawn_file_actions_adddup2(&actions, sv[1], 0);
  posix_spawn_file_actions_adddup2(&actions, sv[1], 1);
  std::vector<char*> argv{const_cast<char*>(path.c_str())};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, path.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(sv[1]);
  if (rc != 0) {
    ::close(sv[0]);
    return makeError(ErrorCode::Internal, "cannot start " + path + ": " + std::strerror(rc));
  }
  return Child{pid, sv[0]};
}

int killAndReap(Child& child) {
  int status = 0;
  if (child.pid > 0) {
    ::kill(child.pid, SIGKILL);
    while (::waitpid(child.pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  if (child.fd >= 0) ::close(child.fd);
  child = Child{};
  return status;
}

std::string describeStatus(int status) {
  return WIFSIGNALED(status) ? "signal " + std::to_string(WTERMSIG(status))
                             : "exit status " + std::to_string(WEXITSTATUS(status));
}

uint64_t residentBytes(pid_t pid) {
  std::ifstream statm("/proc/" + std::to_string(pid) + "/statm");
  unsigned long long size = 0, resident = 0;
  if (!(statm >> size >> resident)) return 0;
  return uint64_t(resident) * uint64_t(sysconf(_SC_PAGESIZE));
}

}  // namespace brdfa::worker_process
