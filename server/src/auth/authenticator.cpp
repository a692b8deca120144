#include "auth/authenticator.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "util/atomic_file.h"
#include "util/auth_crypto.h"

namespace brdfa::server {

namespace fs = std::filesystem;

namespace {

constexpr size_t kMinAdminTokenLength = 16;

std::string firstLine(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
  return line;
}

// The admin token: --admin-token-file, else $BRDFA_ADMIN_TOKEN, else <data-dir>/auth/admin-token,
// made (random, mode 0600) when missing. Replicas sharing the folder agree: the first to start
// creates the file exclusively, the others read it.
Result<std::string> adminToken(const ServerConfig& config, std::vector<std::string>& log) {
  auto readToken = [](const std::string& path) -> Result<std::string> {
    std::ifstream in(path, std::ios::binary);
    if (!in) return makeError(ErrorCode::InvalidArgument, "cannot read the admin token file " + path);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::string token = firstLine(text);
    if (token.size() < kMinAdminTokenLength)
      return makeError(ErrorCode::InvalidArgument, "the admin token in " + path + " is shorter than 16 characters");
    return token;
  };
  if (!config.auth.adminTokenFile.empty()) return readToken(config.auth.adminTokenFile);
  if (const char* env = std::getenv("BRDFA_ADMIN_TOKEN"); env && *env) {
    std::string token = firstLine(env);
    if (token.size() < kMinAdminTokenLength)
      return makeError(ErrorCode::InvalidArgument, "$BRDFA_ADMIN_TOKEN is shorter than 16 characters");
    return token;
  }
  const fs::path path = fs::path(config.dataDir) / "auth" / "admin-token";
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  const std::string fresh = "brdfa_admin_" + randomBase64Url(32);
  // Written whole under a private name, then linked into place: a replica starting in the same
  // instant either wins the link or reads a complete file, never an empty one.
  const fs::path temp = path.parent_path() / (std::string(kTempPrefix) + "admin-token." + randomLowerAlnum(12));
  int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return makeError(ErrorCode::Internal, "cannot write the admin token file " + path.string());
  const std::string line = fresh + "\n";
  const bool written = ::write(fd, line.data(), line.size()) == ssize_t(line.size()) && ::fsync(fd) == 0;
  ::close(fd);
  const bool linked = written && ::link(temp.c_str(), path.c_str()) == 0;
  const int linkError = errno;
  ::unlink(temp.c_str());
  if (linked) {
    log.push_back("auth: made the teacher's token in " + path.string() + " (read it there; it is not logged)");
    return fresh;
  }
  if (!written || linkError != EEXIST)
    return makeError(ErrorCode::Internal, "cannot write the admin token file " + path.string());
  log.push_back("auth: the teacher's token is in " + path.string());
  return readToken(path.string());
}

}  // namespace

Result<std::unique_ptr<Authenticator>> Authenticator::create(const ServerConfig& config,
                                                             std::vector<std::string>& log) {
  std::unique_ptr<Authenticator> auth(new Authenticator());
  auth->settings_ = config.auth;
  switch (config.auth.mode) {
    case AuthMode::None:
      if (!isLoopbackHost(config.host))
        log.push_back("warning: --auth none on " + config.host +
                      ": every client that reaches this port acts as the teacher (reads, changes and deletes "
                      "everything); use --auth tokens for a class");
      break;
    case AuthMode::Tokens: {
      BRDFA_TRY_ASSIGN(std::string token, adminToken(config, log));
      auth->adminDigest_ = sha256Hex(token);
      auth->users_ = std::make_unique<UserStore>((fs::path(config.dataDir) / "auth").string());
      break;
    }
    case AuthMode::Proxy:
      for (const std::string& text : config.auth.proxyFrom) {
        std::optional<AddressRange> range = parseAddressRange(text);
        if (!range)
          return makeError(ErrorCode::InvalidArgument, "--proxy-from '" + text + "' is not an address or range");
        auth->proxyFrom_.push_back(*range);
      }
      break;
  }
  return auth;
}

std::string Authenticator::bearerToken(const httplib::Request& req) {
  const std::string value = req.get_header_value("Authorization");
  if (value.size() < 7) return {};
  std::string scheme = value.substr(0, 7);
  std::transform(scheme.begin(), scheme.end(), scheme.begin(), [](unsigned char c) { return std::tolower(c); });
  if (scheme != "bearer ") return {};
  std::string token = value.substr(7);
  token.erase(0, token.find_first_not_of(' '));
  token.erase(token.find_last_not_of(' ') + 1);
  return token;
}

std::optional<Identity> Authenticator::identify(const httplib::Request& req) const {
  switch (settings_.mode) {
    case AuthMode::None: return localIdentity();
    case AuthMode::Tokens: {
      const std::string token = bearerToken(req);
      if (token.empty()) return std::nullopt;
      if (constantTimeEqual(sha256Hex(token), adminDigest_))
        return Identity{"teacher", "Teacher", Role::Teacher, "admin"};
      return users_->authenticate(token);
    }
    case AuthMode::Proxy: {
      if (!req.has_header(settings_.proxyUserHeader.c_str())) return std::nullopt;
      const bool trusted = std::any_of(proxyFrom_.begin(), proxyFrom_.end(),
                                       [&](const AddressRange& r) { return r.contains(req.remote_addr); });
      if (!trusted) return std::nullopt;
      std::string user = req.get_header_value(settings_.proxyUserHeader.c_str());
      std::transform(user.begin(), user.end(), user.begin(), [](unsigned char c) { return std::tolower(c); });
      if (!isValidUserName(user)) return std::nullopt;
      const bool admin =
          std::find(settings_.proxyAdmins.begin(), settings_.proxyAdmins.end(), user) != settings_.proxyAdmins.end();
      return Identity{user, user, admin ? Role::Teacher : Role::Student, ""};
    }
  }
  return std::nullopt;
}

}  // namespace brdfa::server
