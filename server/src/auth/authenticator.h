// Turns a request into the person it acts for, by the server's --auth mode (docs/api.md,
// Identities and ownership): nobody in particular (none), a bearer token (tokens), or a user
// header from a trusted front (proxy). Thread-safe.
#pragma once

#include <httplib.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "auth/identity.h"
#include "auth/user_store.h"
#include "brdfa/result.h"
#include "config/config.h"
#include "util/address_range.h"

namespace brdfa::server {

class Authenticator {
 public:
  // Reads or makes the admin token (tokens mode); `log` receives where it is, never what.
  static Result<std::unique_ptr<Authenticator>> create(const ServerConfig& config, std::vector<std::string>& log);

  AuthMode mode() const { return settings_.mode; }

  // The person `req` acts for; nullopt when it names nobody this mode accepts (no token, an
  // unknown or revoked one, a user header from an untrusted address).
  std::optional<Identity> identify(const httplib::Request& req) const;

  // The bearer token of a request ("" without one).
  static std::string bearerToken(const httplib::Request& req);

  // The users, tokens and join codes (tokens mode; null otherwise).
  UserStore* users() const { return users_.get(); }

 private:
  AuthSettings settings_;
  std::string adminDigest_;  // SHA-256 of the admin token
  std::vector<AddressRange> proxyFrom_;
  std::unique_ptr<UserStore> users_;
};

}  // namespace brdfa::server
