#include "util/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <vector>

namespace brdfa::server {

namespace fs = std::filesystem;

namespace {

Error ioError(const std::string& what, const fs::path& path, int err) {
  return Error{ErrorCode::Internal, what + " " + path.string() + ": " + std::strerror(err)};
}

Result<void> fsyncDir(const fs::path& dir) {
  int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return ioError("cannot open folder", dir, errno);
  int rc = ::fsync(fd);
  int err = errno;
  ::close(fd);
  if (rc != 0) return ioError("cannot fsync folder", dir, err);
  return {};
}

// Writes `data` to a fresh, fsynced temp file beside `target`; its path, or the error (nothing
// left behind then).
Result<fs::path> writeTempFile(const fs::path& dir, const fs::path& target, std::string_view data) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Error{ErrorCode::Internal, "cannot create folder " + dir.string() + ": " + ec.message()};

  std::string tmpl = (dir / (std::string(kTempPrefix) + target.filename().string() + ".XXXXXX")).string();
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  int fd = ::mkostemp(name.data(), O_CLOEXEC);
  if (fd < 0) return ioError("cannot create temp file in", dir, errno);
  fs::path tmp(name.data());
  auto fail = [&](const std::string& what, int err) -> Result<fs::path> {
    if (fd >= 0) ::close(fd);
    ::unlink(tmp.c_str());
    return ioError(what, tmp, err);
  };
  ::fchmod(fd, 0644);
  const char* p = data.data();
  size_t left = data.size();
  while (left > 0) {
    ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return fail("cannot write", errno);
    }
    p += n;
    left -= static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) return fail("cannot fsync", errno);
  if (::close(fd) != 0) {
    fd = -1;
    return fail("cannot close", errno);
  }
  return tmp;
}

fs::path folderOf(const fs::path& target) {
  fs::path dir = target.parent_path();
  return dir.empty() ? fs::path(".") : dir;
}

}  // namespace

Result<void> writeFileAtomically(const fs::path& target, std::string_view data) {
  const fs::path dir = folderOf(target);
  BRDFA_TRY_ASSIGN(fs::path tmp, writeTempFile(dir, target, data));
  if (::rename(tmp.c_str(), target.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    return ioError("cannot rename over " + target.string() + " from", tmp, err);
  }
  return fsyncDir(dir);
}

Result<void> createFileExclusively(const fs::path& target, std::string_view data, bool& created) {
  created = false;
  const fs::path dir = folderOf(target);
  BRDFA_TRY_ASSIGN(fs::path tmp, writeTempFile(dir, target, data));
  // link(2) fails with EEXIST when the name is taken, where rename(2) would replace it.
  const int rc = ::link(tmp.c_str(), target.c_str());
  const int err = errno;
  ::unlink(tmp.c_str());
  if (rc != 0) {
    if (err == EEXIST) return fsyncDir(dir);
    return ioError("cannot create " + target.string() + " from", tmp, err);
  }
  created = true;
  return fsyncDir(dir);
}

Result<void> removeFileDurably(const fs::path& target) {
  if (::unlink(target.c_str()) != 0) {
    if (errno == ENOENT) return Error{ErrorCode::NotFound, "no file " + target.string()};
    return ioError("cannot remove", target, errno);
  }
  fs::path dir = target.parent_path();
  return fsyncDir(dir.empty() ? fs::path(".") : dir);
}

int removeStaleTempFiles(const fs::path& dir) {
  std::error_code ec;
  int removed = 0;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().filename().string().rfind(kTempPrefix, 0) != 0) continue;
    // Replicas share the folder: a young temp file may be another server's write in progress.
    std::error_code tec;
    const auto written = fs::last_write_time(it->path(), tec);
    if (!tec && fs::file_time_type::clock::now() - written < kTempFileAbandonedAfter) continue;
    std::error_code rec;
    if (fs::remove(it->path(), rec)) ++removed;
  }
  return removed;
}

}  // namespace brdfa::server
