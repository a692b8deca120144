// The people of `tokens` mode, their tokens and the class's join codes, kept in
// <data-dir>/auth/ so that every replica sharing the folder sees the same class:
//   users/<user>.json        {"user", "display_name", "role", "created_at"}
//   tokens/<sha256>.json     {"user", "sha256", "created_at"}   (a token's hash, never the token)
//   join-codes/<sha256>.json {"sha256", "created_at", "expires_at"}
// A token is valid while its file exists: revoking unlinks it, so the next request anywhere
// fails. Every write is atomic (atomic_file.h); a user name is taken with an exclusive create.
// Thread-safe.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "auth/identity.h"
#include "brdfa/result.h"

namespace brdfa::server {

struct UserRecord {
  std::string user, displayName;
  Role role = Role::Student;
  std::string createdAt;  // ISO 8601 UTC
};

struct TokenInfo {
  std::string id;  // the first 16 hex digits of its SHA-256: names it for revocation
  std::string user;
  std::string createdAt;
};

struct JoinCodeInfo {
  std::string id;  // the first 16 hex digits of the code's SHA-256
  std::string createdAt, expiresAt;
  int64_t expiresUnix = 0;
};

// A new secret and what names it; the secret is shown once, to whoever asked for it.
struct IssuedToken {
  std::string token, id;
};

class UserStore {
 public:
  // `dir` is <data-dir>/auth; created on the first write.
  explicit UserStore(std::string dir);

  // The person a presented token belongs to (nullopt: unknown or revoked). Costs one stat of
  // the token's file, and a read only when the file changed since the last look.
  std::optional<Identity> authenticate(std::string_view token) const;

  // A new user; Conflict-like InvalidArgument when the name is not valid, `taken` set when it
  // is someone's already.
  Result<UserRecord> addUser(const std::string& user, const std::string& displayName, Role role, bool& taken);
  // A new student named after `displayName` (userNameFromDisplayName, then -2, -3, ... until free).
  Result<UserRecord> addStudentNamedAfter(const std::string& displayName);
  std::optional<UserRecord> findUser(std::string_view user) const;
  std::vector<UserRecord> listUsers() const;
  // Revokes every token of `user` and forgets the user; false when there is no such user.
  Result<bool> removeUser(std::string_view user);

  Result<IssuedToken> issueToken(const std::string& user);
  std::vector<TokenInfo> listTokens() const;
  // Revokes the token `id` of `user`; false when `user` has no such token.
  Result<bool> revokeToken(std::string_view user, std::string_view id);
  // Revokes the token itself (logout).
  Result<void> revokePresented(std::string_view token);

  // A join code valid for `ttlMinutes`; the code itself is returned once.
  Result<std::pair<std::string, JoinCodeInfo>> issueJoinCode(int ttlMinutes);
  // Whether `code` is a code that exists and has not expired.
  bool joinCodeValid(std::string_view code) const;
  std::vector<JoinCodeInfo> listJoinCodes() const;  // unexpired ones
  Result<bool> revokeJoinCode(std::string_view id);

 private:
  std::string usersDir() const;
  std::string tokensDir() const;
  std::string codesDir() const;

  const std::string dir_;
  // A token file as last read: its stamp, so an unchanged file is not read again.
  struct CachedToken {
    uint64_t inode = 0;
    int64_t mtimeNs = 0;
    Identity identity;
  };
  mutable std::mutex mutex_;
  mutable std::map<std::string, CachedToken, std::less<>> tokens_;  // by SHA-256
};

// ISO 8601 UTC of a Unix time ("2026-12-04T13:28:09Z").
std::string isoTimeUtc(int64_t unixSeconds);

}  // namespace brdfa::server
