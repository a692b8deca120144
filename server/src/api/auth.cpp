// Who am I, joining a class, and the teacher's users, tokens and join codes (docs/api.md,
// Identities and ownership). Tokens and codes are shown once, in the answer that makes them.
#include "api/routes.h"
#include "http/http_errors.h"

namespace brdfa::server {

namespace {

constexpr int kDefaultJoinCodeMinutes = 240;
constexpr int kMaxJoinCodeMinutes = 7 * 24 * 60;
constexpr size_t kMaxUsers = 1000;  // a leaked join code cannot fill the disk with users

nlohmann::json quotasJson(const Service& service, const Identity& who) {
  if (who.teacher()) return nullptr;
  const Quotas& q = service.config.quotas;
  return {{"sessions", q.sessions},        {"brdfs", q.brdfs}, {"uploads", q.uploads},
          {"upload_bytes", q.uploadBytes}, {"jobs", q.jobs},   {"renders", q.renders}};
}

// The user store of tokens mode; in the other modes answers 400 unsupported and returns null.
UserStore* tokenStore(Service& service, httplib::Response& res) {
  if (UserStore* users = service.auth->users()) return users;
  sendError(res, ErrorCode::Unsupported,
            std::string("there are no tokens to manage with --auth ") + authModeName(service.auth->mode()));
  return nullptr;
}

// The store a teacher-only token route works on; null after a 403 (not the teacher) or a 400.
UserStore* teachersTokenStore(Service& service, const httplib::Request& req, httplib::Response& res) {
  return requireTeacher(req, res) ? tokenStore(service, res) : nullptr;
}

void sendStoreError(httplib::Response& res, const Error& error) {
  sendError(res, ErrorCode::StorageError, error.message);
}

void registerSelfRoutes(httplib::Server& server, Service& service) {
  server.Get("/api/auth/me", [&service](const httplib::Request& req, httplib::Response& res) {
    const Identity& who = requester(req);
    sendJson(res, {{"mode", authModeName(service.auth->mode())},
                   {"user", who.user.empty() ? nlohmann::json(nullptr) : nlohmann::json(who.user)},
                   {"display_name", who.displayName},
                   {"role", roleName(who.role)},
                   {"namespace", who.brdfNamespace()},
                   {"quotas", quotasJson(service, who)}});
  });

  server.Post("/api/auth/join", [&service](const httplib::Request& req, httplib::Response& res) {
    UserStore* users = tokenStore(service, res);
    if (!users) return;
    auto body = readJsonBody(req, res);
    if (!body) return;
    if (!body->is_object() || !body->contains("code") || !(*body)["code"].is_string())
      return sendError(res, ErrorCode::InvalidArgument, "send {\"code\": \"...\", \"display_name\": \"...\"}", "code");
    const std::string displayName = (*body).contains("display_name") && (*body)["display_name"].is_string()
                                        ? cleanDisplayName((*body)["display_name"].get<std::string>())
                                        : std::string();
    if (displayName.empty())
      return sendError(res, ErrorCode::InvalidArgument, "display_name: pick a name to show (1-64 characters)",
                       "display_name");
    if (!users->joinCodeValid((*body)["code"].get<std::string>()))
      return sendError(res, ErrorCode::NotFound, "this join code is unknown, expired or withdrawn; ask for a new link",
                       "code");
    if (users->listUsers().size() >= kMaxUsers)
      return sendError(res, ErrorCode::StorageFull, "the class has " + std::to_string(kMaxUsers) + " users already");
    Result<UserRecord> user = users->addStudentNamedAfter(displayName);
    if (!user) return sendStoreError(res, user.error());
    Result<IssuedToken> token = users->issueToken(user->user);
    if (!token) return sendStoreError(res, token.error());
    sendJson(res,
             {{"token", token->token},
              {"token_id", token->id},
              {"user", user->user},
              {"display_name", user->displayName},
              {"role", "student"}},
             201);
  });

  server.Post("/api/auth/logout", [&service](const httplib::Request& req, httplib::Response& res) {
    UserStore* users = tokenStore(service, res);
    if (!users) return;
    if (requester(req).tokenId.empty())
      return sendError(res, ErrorCode::Unsupported,
                       "the admin token is revoked by changing it where the server reads it");
    if (Result<void> revoked = users->revokePresented(Authenticator::bearerToken(req)); !revoked)
      return sendStoreError(res, revoked.error());
    res.status = 204;
  });
}

void registerJoinCodeRoutes(httplib::Server& server, Service& service) {
  server.Post("/api/auth/join-codes", [&service](const httplib::Request& req, httplib::Response& res) {
    UserStore* users = teachersTokenStore(service, req, res);
    if (!users) return;
    int minutes = kDefaultJoinCodeMinutes;
    if (!req.body.empty()) {
      auto body = readJsonBody(req, res);
      if (!body) return;
      if (body->is_object() && body->contains("ttl_minutes")) {
        const nlohmann::json& ttl = (*body)["ttl_minutes"];
        if (!ttl.is_number_integer() || ttl.get<int64_t>() < 1 || ttl.get<int64_t>() > kMaxJoinCodeMinutes)
          return sendError(res, ErrorCode::InvalidArgument,
                           "ttl_minutes must be an integer in [1, " + std::to_string(kMaxJoinCodeMinutes) + "]",
                           "ttl_minutes");
        minutes = ttl.get<int>();
      }
    }
    auto issued = users->issueJoinCode(minutes);
    if (!issued) return sendStoreError(res, issued.error());
    const auto& [code, info] = issued.value();
    sendJson(res,
             {{"code", code},
              {"id", info.id},
              {"created_at", info.createdAt},
              {"expires_at", info.expiresAt},
              {"join_path", "/?join=" + code}},
             201);
  });

  server.Get("/api/auth/join-codes", [&service](const httplib::Request& req, httplib::Response& res) {
    UserStore* users = teachersTokenStore(service, req, res);
    if (!users) return;
    nlohmann::json out = nlohmann::json::array();
    for (const JoinCodeInfo& c : users->listJoinCodes())
      out.push_back({{"id", c.id}, {"created_at", c.createdAt}, {"expires_at", c.expiresAt}});
    sendJson(res, out);
  });

  server.Delete("/api/auth/join-codes/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    UserStore* users = teachersTokenStore(service, req, res);
    if (!users) return;
    Result<bool> revoked = users->revokeJoinCode(std::string(req.matches[1]));
    if (!revoked) return sendStoreError(res, revoked.error());
    if (!revoked.value()) return sendError(res, ErrorCode::NotFound, "no join code with that id", "id");
    res.status = 204;
  });
}

void registerUserRoutes(httplib::Server& server, Service& service) {
  server.Get("/api/auth/users", [&service](const httplib::Request& req, httplib::Response& res) {
    UserStore* users = teachersTokenStore(service, req, res);
    if (!users) return;
    const std::vector<TokenInfo> tokens = users->listTokens();
    nlohmann::json out = nlohmann::json::array();
    for (const UserRecord& u : users->listUsers()) {
      nlohmann::json theirs = nlohmann::json::array();
      for (const TokenInfo& t : tokens)
        if (t.user == u.user) theirs.push_back({{"id", t.id}, {"created_at", t.createdAt}});
      out.push_back({{"user", u.user},
                     {"display_name", u.displayName},
                     {"role", roleName(u.role)},
                     {"created_at", u.createdAt},
                     {"tokens", theirs}});
    }
    sendJson(res, out);
  });

  server.Post("/api/auth/users", [&service](const httplib::Request& req, httplib::Response& res) {
    UserStore* users = teachersTokenStore(service, req, res);
    if (!users) return;
    auto body = readJsonBody(req, res);
    if (!body) return;
    if (!body->is_object() || !body->contains("user") || !(*body)["user"].is_string())
      return sendError(res, ErrorCode::InvalidArgument, "send {\"user\": \"alice\"} (display_name and role optional)",
                       "user");
    const std::string user = (*body)["user"].get<std::string>();
    if (!isValidUserName(user) || isReservedUserName(user))
      return sendError(res, ErrorCode::InvalidArgument,
                       "user names are 1-64 of [a-z0-9._@-], starting with a letter or digit, and not a reserved word",
                       "user");
    std::string display = user;
    if (body->contains("display_name")) {
      if (!(*body)["display_name"].is_string() || cleanDisplayName((*body)["display_name"].get<std::string>()).empty())
        return sendError(res, ErrorCode::InvalidArgument, "display_name must be 1-64 characters of text",
                         "display_name");
      display = cleanDisplayName((*body)["display_name"].get<std::string>());
    }
    Role role = Role::Student;
    if (body->contains("role")) {
      const nlohmann::json& r = (*body)["role"];
      std::optional<Role> named = r.is_string() ? roleFromName(r.get<std::string>()) : std::nullopt;
      if (!named) return sendError(res, ErrorCode::InvalidArgument, "role is \"student\" or \"teacher\"", "role");
      role = *named;
    }
    if (users->listUsers().size() >= kMaxUsers)
      return sendError(res, ErrorCode::StorageFull, "the class has " + std::to_string(kMaxUsers) + " users already");
    bool taken = false;
    Result<UserRecord> made = users->addUser(user, display, role, taken);
    if (taken) return sendError(res, ErrorCode::Conflict, "user '" + user + "' exists already", "user");
    if (!made) return sendStoreError(res, made.error());
    Result<IssuedToken> token = users->issueToken(user);
    if (!token) return sendStoreError(res, token.error());
    sendJson(res,
             {{"user", made->user},
              {"display_name", made->displayName},
              {"role", roleName(made->role)},
              {"token", token->token},
              {"token_id", token->id}},
             201);
  });

  server.Post("/api/auth/users/([^/]+)/tokens", [&service](const httplib::Request& req, httplib::Response& res) {
    UserStore* users = teachersTokenStore(service, req, res);
    if (!users) return;
    const std::string user = req.matches[1];
    if (!users->findUser(user)) return sendError(res, ErrorCode::NotFound, "no user '" + user + "'", "user");
    Result<IssuedToken> token = users->issueToken(user);
    if (!token) return sendStoreError(res, token.error());
    sendJson(res, {{"token", token->token}, {"token_id", token->id}}, 201);
  });

  server.Delete("/api/auth/users/([^/]+)/tokens/([^/]+)",
                [&service](const httplib::Request& req, httplib::Response& res) {
                  UserStore* users = teachersTokenStore(service, req, res);
                  if (!users) return;
                  Result<bool> revoked = users->revokeToken(std::string(req.matches[1]), std::string(req.matches[2]));
                  if (!revoked) return sendStoreError(res, revoked.error());
                  if (!revoked.value())
                    return sendError(res, ErrorCode::NotFound, "that user has no token with that id", "id");
                  res.status = 204;
                });

  server.Delete("/api/auth/users/([^/]+)", [&service](const httplib::Request& req, httplib::Response& res) {
    UserStore* users = teachersTokenStore(service, req, res);
    if (!users) return;
    Result<bool> removed = users->removeUser(std::string(req.matches[1]));
    if (!removed) return sendStoreError(res, removed.error());
    if (!removed.value())
      return sendError(res, ErrorCode::NotFound, "no user '" + std::string(req.matches[1]) + "'", "user");
    res.status = 204;
  });
}

}  // namespace

void registerAuthRoutes(httplib::Server& server, Service& service) {
  registerSelfRoutes(server, service);
  registerJoinCodeRoutes(server, service);
  registerUserRoutes(server, service);
}

}  // namespace brdfa::server
