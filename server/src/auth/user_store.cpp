#include "auth/user_store.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "util/atomic_file.h"
#include "util/auth_crypto.h"
#include "util/display_text.h"

namespace brdfa::server {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr size_t kTokenIdLength = 16;
constexpr const char* kTokenPrefix = "brdfa_";

std::optional<json> readJsonFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  json j = json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return std::nullopt;
  return j;
}

std::string stringField(const json& j, const char* key) {
  auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::string();
}

std::optional<UserRecord> userFromJson(const json& j) {
  UserRecord r;
  r.user = stringField(j, "user");
  if (!isValidUserName(r.user)) return std::nullopt;
  r.displayName = stringField(j, "display_name");
  r.role = roleFromName(stringField(j, "role")).value_or(Role::Student);
  r.createdAt = stringField(j, "created_at");
  return r;
}

json userToJson(const UserRecord& r) {
  return {{"user", r.user}, {"display_name", r.displayName}, {"role", roleName(r.role)}, {"created_at", r.createdAt}};
}

// `length` lower-case hex digits: a stored hash (64) or an id (16). Only such names are ever
// turned into paths.
bool isHex(std::string_view s, size_t length) {
  if (s.size() != length) return false;
  for (char c : s)
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  return true;
}
bool isHexDigest(std::string_view s) { return isHex(s, 64); }
bool isIdPrefix(std::string_view id) { return isHex(id, kTokenIdLength); }

// Calls fn(digest, json) for every <dir>/<64 hex>.json that parses.
template <class Fn>
void forEachRecord(const std::string& dir, Fn fn) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& p = it->path();
    if (p.extension() != ".json" || !isHexDigest(p.stem().string())) continue;
    if (std::optional<json> j = readJsonFile(p)) fn(p.stem().string(), *j);
  }
}

int64_t unixNow() {
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

std::string isoTimeUtc(int64_t unixSeconds) {
  const std::time_t secs = static_cast<std::time_t>(unixSeconds);
  std::tm utc{};
  gmtime_r(&secs, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

UserStore::UserStore(std::string dir) : dir_(std::move(dir)) {}

std::string UserStore::usersDir() const { return (fs::path(dir_) / "users").string(); }
std::string UserStore::tokensDir() const { return (fs::path(dir_) / "tokens").string(); }
std::string UserStore::codesDir() const { return (fs::path(dir_) / "join-codes").string(); }

std::optional<Identity> UserStore::authenticate(std::string_view token) const {
  if (token.size() < 16 || token.size() > 256) return std::nullopt;
  const std::string digest = sha256Hex(token);
  const fs::path path = fs::path(tokensDir()) / (digest + ".json");
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {  // revoked (or never issued): forget it here too
    std::lock_guard lock(mutex_);
    tokens_.erase(digest);
    return std::nullopt;
  }
  const int64_t mtime = int64_t(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec;
  {
    std::lock_guard lock(mutex_);
    auto it = tokens_.find(digest);
    if (it != tokens_.end() && it->second.inode == st.st_ino && it->second.mtimeNs == mtime) return it->second.identity;
  }
  std::optional<json> record = readJsonFile(path);
  // The record names its own hash: compared in constant time, so a file put in place under
  // another name never stands for this token.
  if (!record || !constantTimeEqual(stringField(*record, "sha256"), digest)) return std::nullopt;
  std::optional<UserRecord> user = findUser(stringField(*record, "user"));
  if (!user) return std::nullopt;
  Identity who{user->user, user->displayName, user->role, digest.substr(0, kTokenIdLength)};
  std::lock_guard lock(mutex_);
  tokens_[digest] = CachedToken{uint64_t(st.st_ino), mtime, who};
  return who;
}

Result<UserRecord> UserStore::addUser(const std::string& user, const std::string& displayName, Role role, bool& taken) {
  taken = false;
  if (!isValidUserName(user))
    return makeError(ErrorCode::InvalidArgument,
                     "user: 1-64 of [a-z0-9._@-], starting with a letter or digit, got '" + user.substr(0, 64) + "'",
                     "user");
  UserRecord r{user, displayName.empty() ? user : displayName, role, nowIso8601()};
  bool created = false;
  Result<void> written =
      createFileExclusively(fs::path(usersDir()) / (user + ".json"), userToJson(r).dump(2) + "\n", created);
  if (!written) return written.takeError();
  if (!created) {
    taken = true;
    return makeError(ErrorCode::InvalidArgument, "the user name '" + user + "' is taken", "user");
  }
  return r;
}

Result<UserRecord> UserStore::addStudentNamedAfter(const std::string& displayName) {
  const std::string base = userNameFromDisplayName(displayName);
  for (int n = 1; n <= 1000; ++n) {
    const std::string name = n == 1 ? base : base + "-" + std::to_string(n);
    if (isReservedUserName(name)) continue;
    bool taken = false;
    Result<UserRecord> r = addUser(name, displayName, Role::Student, taken);
    if (r || !taken) return r;
  }
  return makeError(ErrorCode::InvalidArgument, "every user name made from this display name is taken; pick another",
                   "display_name");
}

std::optional<UserRecord> UserStore::findUser(std::string_view user) const {
  if (!isValidUserName(user)) return std::nullopt;
  std::optional<json> j = readJsonFile(fs::path(usersDir()) / (std::string(user) + ".json"));
  return j ? userFromJson(*j) : std::nullopt;
}

std::vector<UserRecord> UserStore::listUsers() const {
  std::vector<UserRecord> out;
  std::error_code ec;
  for (fs::directory_iterator it(usersDir(), ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().extension() != ".json") continue;
    if (std::optional<json> j = readJsonFile(it->path()))
      if (std::optional<UserRecord> r = userFromJson(*j)) out.push_back(std::move(*r));
  }
  std::sort(out.begin(), out.end(), [](const UserRecord& a, const UserRecord& b) { return a.user < b.user; });
  return out;
}

Result<bool> UserStore::removeUser(std::string_view user) {
  if (!findUser(user)) return false;
  // Tokens first: a user whose record is gone but whose token is not would still be refused
  // (authenticate needs both), but no stray token should outlive its user.
  for (const TokenInfo& t : listTokens())
    if (t.user == user) {
      BRDFA_TRY(revokeToken(user, t.id));
    }
  Result<void> removed = removeFileDurably(fs::path(usersDir()) / (std::string(user) + ".json"));
  if (!removed && removed.error().code != ErrorCode::NotFound) return removed.takeError();
  return true;
}

Result<IssuedToken> UserStore::issueToken(const std::string& user) {
  const std::string secret = randomBase64Url(32);
  if (secret.empty()) return makeError(ErrorCode::Internal, "the random generator failed");
  const std::string token = kTokenPrefix + secret;
  const std::string digest = sha256Hex(token);
  const json record{{"user", user}, {"sha256", digest}, {"created_at", nowIso8601()}};
  BRDFA_TRY(writeFileAtomically(fs::path(tokensDir()) / (digest + ".json"), record.dump() + "\n"));
  return IssuedToken{token, digest.substr(0, kTokenIdLength)};
}

std::vector<TokenInfo> UserStore::listTokens() const {
  std::vector<TokenInfo> out;
  forEachRecord(tokensDir(), [&](const std::string& digest, const json& j) {
    out.push_back(TokenInfo{digest.substr(0, kTokenIdLength), stringField(j, "user"), stringField(j, "created_at")});
  });
  return out;
}

Result<bool> UserStore::revokeToken(std::string_view user, std::string_view id) {
  if (!isIdPrefix(id)) return false;
  std::optional<std::string> match;
  forEachRecord(tokensDir(), [&](const std::string& digest, const json& j) {
    if (digest.compare(0, kTokenIdLength, id) == 0 && stringField(j, "user") == user) match = digest;
  });
  if (!match) return false;
  Result<void> removed = removeFileDurably(fs::path(tokensDir()) / (*match + ".json"));
  if (!removed && removed.error().code != ErrorCode::NotFound) return removed.takeError();
  std::lock_guard lock(mutex_);
  tokens_.erase(*match);
  return true;
}

Result<void> UserStore::revokePresented(std::string_view token) {
  const std::string digest = sha256Hex(token);
  Result<void> removed = removeFileDurably(fs::path(tokensDir()) / (digest + ".json"));
  {
    std::lock_guard lock(mutex_);
    tokens_.erase(digest);
  }
  if (!removed && removed.error().code != ErrorCode::NotFound) return removed.takeError();
  return {};
}

Result<std::pair<std::string, JoinCodeInfo>> UserStore::issueJoinCode(int ttlMinutes) {
  const std::string code = randomLowerAlnum(16);
  if (code.empty()) return makeError(ErrorCode::Internal, "the random generator failed");
  const std::string digest = sha256Hex(code);
  const int64_t now = unixNow();
  JoinCodeInfo info{digest.substr(0, kTokenIdLength), isoTimeUtc(now), isoTimeUtc(now + int64_t(ttlMinutes) * 60),
                    now + int64_t(ttlMinutes) * 60};
  const json record{{"sha256", digest},
                    {"created_at", info.createdAt},
                    {"expires_at", info.expiresAt},
                    {"expires_unix", info.expiresUnix}};
  BRDFA_TRY(writeFileAtomically(fs::path(codesDir()) / (digest + ".json"), record.dump() + "\n"));
  return std::make_pair(code, info);
}

bool UserStore::joinCodeValid(std::string_view code) const {
  if (code.empty() || code.size() > 64) return false;
  const std::string digest = sha256Hex(code);
  std::optional<json> j = readJsonFile(fs::path(codesDir()) / (digest + ".json"));
  if (!j || !constantTimeEqual(stringField(*j, "sha256"), digest)) return false;
  auto it = j->find("expires_unix");
  return it != j->end() && it->is_number_integer() && it->get<int64_t>() > unixNow();
}

std::vector<JoinCodeInfo> UserStore::listJoinCodes() const {
  std::vector<JoinCodeInfo> out;
  const int64_t now = unixNow();
  forEachRecord(codesDir(), [&](const std::string& digest, const json& j) {
    auto it = j.find("expires_unix");
    const int64_t expires = it != j.end() && it->is_number_integer() ? it->get<int64_t>() : 0;
    if (expires > now)
      out.push_back(JoinCodeInfo{digest.substr(0, kTokenIdLength), stringField(j, "created_at"),
                                 stringField(j, "expires_at"), expires});
  });
  std::sort(out.begin(), out.end(),
            [](const JoinCodeInfo& a, const JoinCodeInfo& b) { return a.createdAt < b.createdAt; });
  return out;
}

Result<bool> UserStore::revokeJoinCode(std::string_view id) {
  if (!isIdPrefix(id)) return false;
  std::optional<std::string> match;
  forEachRecord(codesDir(), [&](const std::string& digest, const json&) {
    if (digest.compare(0, kTokenIdLength, id) == 0) match = digest;
  });
  if (!match) return false;
  Result<void> removed = removeFileDurably(fs::path(codesDir()) / (*match + ".json"));
  if (!removed && removed.error().code != ErrorCode::NotFound) return removed.takeError();
  return true;
}

}  // namespace brdfa::server
