// Identities, ownership, quotas and browser safety (docs/auth.md): the real server in `tokens`
// mode with a teacher (the admin token) and two students, alice and bob. The matrix sends every
// route of docs/api.md as each of them and as nobody, and checks the status of each cell; where
// someone else's thing answers 404 it must answer exactly as a thing that does not exist. Then
// quotas per student, token and join-code life cycles, cross-site refusals, and the other modes
// (`none`, `proxy`) with their start-up rules.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "brdfa/image_codec.h"
#include "image_test_encoders.h"
#include "server_fixture.h"

namespace brdfa::itest {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;
using Vars = std::map<std::string, std::string>;

// ---- SHA-256 (FIPS 180-4), to find a token's stored hash -----------------------------------

std::string sha256Hex(std::string_view message) {
  static constexpr uint32_t k[64] = {
      0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
      0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
      0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
      0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
      0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
      0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
      0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
      0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};
  uint32_t h[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  std::string m(message);
  const uint64_t bits = uint64_t(message.size()) * 8;
  m += char(0x80);
  while (m.size() % 64 != 56) m += char(0);
  for (int i = 7; i >= 0; --i) m += char((bits >> (i * 8)) & 0xff);
  auto rotr = [](uint32_t x, int n) { return (x >> n) | (x << (32 - n)); };
  for (size_t off = 0; off < m.size(); off += 64) {
    uint32_t w[64];
    for (int i = 0; i < 16; ++i)
      w[i] = uint32_t(uint8_t(m[off + 4 * i])) << 24 | uint32_t(uint8_t(m[off + 4 * i + 1])) << 16 |
             uint32_t(uint8_t(m[off + 4 * i + 2])) << 8 | uint32_t(uint8_t(m[off + 4 * i + 3]));
    for (int i = 16; i < 64; ++i) {
      const uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
      const uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
      w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
    for (int i = 0; i < 64; ++i) {
      const uint32_t t1 = hh + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + k[i] + w[i];
      const uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
      hh = g;
      g = f;
      f = e;
      e = d + t1;
      d = c;
      c = b;
      b = a;
      a = t1 + t2;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e, h[5] += f, h[6] += g, h[7] += hh;
  }
  char hex[65];
  for (int i = 0; i < 8; ++i) std::snprintf(hex + 8 * i, 9, "%08x", h[i]);
  return std::string(hex, 64);
}

// ---- Test files and scenes -------------------------------------------------------------------

std::string pngFile(int w, int h, bool noise) {
  std::vector<uint8_t> px(size_t(w) * h * 4, 200);
  uint32_t state = 777;
  for (size_t i = 0; i < px.size(); ++i) {
    state = state * 1664525u + 1013904223u;
    px[i] = (i % 4 == 3) ? 255 : noise ? uint8_t(state >> 24) : uint8_t(90);
  }
  std::vector<uint8_t> bytes = encodePng(px.data(), w, h);
  return std::string(bytes.begin(), bytes.end());
}

// An equirectangular environment (width = 2 height).
std::string hdrFile() {
  std::vector<float> px;
  for (int i = 0; i < 32 * 16; ++i) px.insert(px.end(), {0.5f, 0.6f, 0.7f});
  return testing::encodeHdr(32, 16, px);
}

// The smallest scene there is: a 16x16 furnace sphere, a few samples.
json tinyScene(const std::string& brdf = "lambert") { return furnaceScene(brdf, json::object(), 16, 8, 4); }
json tinySceneIn(const std::string& environment) {
  json s = tinyScene();
  s["environment"]["name"] = environment;
  return s;
}
json renderBody(const json& scene) { return {{"scene", scene}, {"spp", 1}}; }
// A strategy comparison that runs for minutes (until cancelled) or a moment.
json comparison(const json& scene, bool long_) {
  return {{"scene", scene},
          {"modes", {"cosine"}},
          {"time_ms", long_ ? 60000 : 100},
          {"reference_ms", long_ ? 240000 : 100}};
}

// ---- HTTP ------------------------------------------------------------------------------------

struct Reply {
  int status = 0;
  std::string body;
  httplib::Headers headers;
  std::string transport;  // why no answer came, when none did
  // The body as JSON; null when it is not JSON.
  json j() const {
    json parsed = json::parse(body, nullptr, /*allow_exceptions=*/false);
    return parsed.is_discarded() ? json() : parsed;
  }
  std::string header(const std::string& name) const {
    auto it = headers.find(name);
    return it == headers.end() ? std::string() : it->second;
  }
  std::string error() const {
    json b = j();
    return b.is_object() && b.contains("error") && b["error"].is_string() ? b["error"].get<std::string>() : "";
  }
};

// j[key] as a T, or `fallback` when j is no object, lacks the key or holds another type: a
// server that answers something unexpected fails an expectation, not the whole run.
template <class T>
T jv(const json& j, const std::string& key, T fallback) {
  if (!j.is_object()) return fallback;
  auto it = j.find(key);
  if (it == j.end()) return fallback;
  if constexpr (std::is_same_v<T, bool>) {
    return it->is_boolean() ? it->get<bool>() : fallback;
  } else if constexpr (std::is_arithmetic_v<T>) {
    return it->is_number() ? it->get<T>() : fallback;
  } else {
    return it->is_string() ? it->get<std::string>() : fallback;
  }
}
std::string jv(const json& j, const std::string& key, const char* fallback) {
  return jv<std::string>(j, key, fallback);
}
// j[key], or null.
json field(const json& j, const std::string& key) { return j.is_object() && j.contains(key) ? j.at(key) : json(); }

std::ostream& operator<<(std::ostream& os, const Reply& r) {
  if (r.status == 0) return os << "no answer (" << r.transport << ")";
  return os << r.status << " " << r.body.substr(0, 400);
}

Reply fromResult(const httplib::Result& r) {
  Reply out;
  if (!r) {
    out.transport = httplib::to_string(r.error());
    return out;
  }
  out.status = r->status;
  out.body = r->body;
  out.headers = r->headers;
  return out;
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The names of any Access-Control-Allow-* headers of a reply ("" when none).
std::string corsHeaders(const Reply& r) {
  std::string found;
  for (const auto& [name, value] : r.headers)
    if (lower(name).rfind("access-control-allow", 0) == 0) found += name + ": " + value + "; ";
  return found;
}

// Writes a request by hand on a loopback connection from `source` and returns its socket
// (-1 on failure): for streams that never end, renders that must stay in flight, and client
// addresses other than 127.0.0.1.
int openRaw(int port, const std::string& method, const std::string& path, const httplib::Headers& headers,
            const std::string& body, const char* source = "127.0.0.1") {
  int fd = connectTo(port, source);
  if (fd < 0) return -1;
  timeval tv{30, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::string req =
      method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\nConnection: close\r\n";
  for (const auto& [name, value] : headers) req += name + ": " + value + "\r\n";
  if (!body.empty() || method != "GET") req += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  req += "\r\n" + body;
  if (!sendAll(fd, req)) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// Reads a reply's status and headers from `fd`, and its body unless it is a stream; closes fd.
Reply readRaw(int fd) {
  Reply out;
  if (fd < 0) {
    out.transport = "connect failed";
    return out;
  }
  std::string in;
  char buf[8192];
  size_t end;
  while ((end = in.find("\r\n\r\n")) == std::string::npos) {
    ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    in.append(buf, size_t(n));
  }
  if (end == std::string::npos) {
    ::close(fd);
    out.transport = "no complete header";
    return out;
  }
  std::istringstream head(in.substr(0, end));
  std::string line;
  std::getline(head, line);
  if (line.size() >= 12) out.status = std::atoi(line.c_str() + 9);
  while (std::getline(head, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(' '));
    out.headers.emplace(line.substr(0, colon), value);
  }
  out.body = in.substr(end + 4);
  const std::string type = out.header("Content-Type");
  if (type.rfind("multipart/", 0) != 0 && out.headers.count("Content-Length")) {
    const size_t want = std::stoul(out.header("Content-Length"));
    while (out.body.size() < want) {
      ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) break;
      out.body.append(buf, size_t(n));
    }
  }
  ::close(fd);
  return out;
}

Reply rawRequest(int port, const std::string& method, const std::string& path, const httplib::Headers& headers,
                 const std::string& body = "", const char* source = "127.0.0.1") {
  return readRaw(openRaw(port, method, path, headers, body, source));
}

httplib::Headers bearer(const std::string& token) {
  httplib::Headers h;
  if (!token.empty()) h.emplace("Authorization", "Bearer " + token);
  return h;
}

// Every token and join code any test was given: none may appear in a file of the data folder
// or in the server's log.
std::set<std::string>& secrets() {
  static std::set<std::string> all;
  return all;
}

// A server this file starts: its own temp folder holding the data folder and, outside it, the
// admin token file.
struct TestServer {
  std::string root, dataDir, adminToken;
  ServerProcess proc;
  std::string startError;

  // Starts in `tokens` mode with `flags` added; "" on success.
  std::string startTokens(const std::vector<std::string>& flags) {
    char tmpl[] = "/tmp/brdfa-auth-XXXXXX";
    if (!::mkdtemp(tmpl)) return "mkdtemp failed";
    root = tmpl;
    dataDir = root + "/data";
    adminToken = "teacher-token-0123456789abcdefgh";  // 32 characters
    secrets().insert(adminToken);
    std::ofstream(root + "/admin-token") << adminToken << "\n";
    ::chmod((root + "/admin-token").c_str(), 0600);
    std::vector<std::string> args = {"--data-dir", dataDir,  "--idle-timeout",     "3",
                                     "--auth",     "tokens", "--admin-token-file", root + "/admin-token"};
    args.insert(args.end(), flags.begin(), flags.end());
    return proc.start(args);
  }
  // Starts with exactly `flags` (another mode) on a data folder of its own.
  std::string startWith(const std::vector<std::string>& flags) {
    char tmpl[] = "/tmp/brdfa-auth-XXXXXX";
    if (!::mkdtemp(tmpl)) return "mkdtemp failed";
    root = tmpl;
    dataDir = root + "/data";
    std::vector<std::string> args = {"--data-dir", dataDir, "--idle-timeout", "3"};
    args.insert(args.end(), flags.begin(), flags.end());
    return proc.start(args);
  }
  ~TestServer() {
    if (proc.running()) proc.terminate();
    if (!root.empty()) {
      std::error_code ec;
      fs::remove_all(root, ec);
    }
  }
  int port() const { return proc.port(); }
  std::string log() const { return proc.logTail(std::string::npos); }

  // One request as `token` ("" = nobody), with `extra` headers.
  Reply call(const std::string& token, const std::string& method, const std::string& path, const std::string& body = "",
             const std::string& type = "application/json", const httplib::Headers& extra = {}) const {
    httplib::Request req;
    req.method = method;
    req.path = path;
    req.headers = bearer(token);
    for (const auto& h : extra) req.headers.insert(h);
    if (!body.empty() || method == "POST" || method == "PUT" || method == "PATCH") {
      req.body = body;
      if (!type.empty()) req.headers.emplace("Content-Type", type);
    }
    auto cli = proc.client();
    return fromResult(cli->send(req));
  }
  Reply get(const std::string& token, const std::string& path) const { return call(token, "GET", path); }
  Reply post(const std::string& token, const std::string& path, const json& body) const {
    return call(token, "POST", path, body.dump());
  }
  Reply upload(const std::string& token, const std::string& bytes, const std::string& fileName,
               const httplib::Headers& extra = {}) const {
    httplib::Headers h = bearer(token);
    for (const auto& e : extra) h.insert(e);
    httplib::MultipartFormDataItems items = {{"file", bytes, fileName, ""}};
    return fromResult(proc.client()->Post("/api/assets", h, items));
  }

  // A new student made by the teacher; their token.
  std::string newStudent(const std::string& user, const std::string& displayName = "") {
    json body{{"user", user}};
    if (!displayName.empty()) body["display_name"] = displayName;
    Reply r = post(adminToken, "/api/auth/users", body);
    EXPECT_EQ(r.status, 201) << "POST /api/auth/users " << body.dump() << ": " << r;
    std::string token = jv(r.j(), "token", "");
    if (!token.empty()) secrets().insert(token);
    return token;
  }
  // A join code made by the teacher: {code, id}.
  std::pair<std::string, std::string> newJoinCode(int ttlMinutes = 30) {
    Reply r = post(adminToken, "/api/auth/join-codes", {{"ttl_minutes", ttlMinutes}});
    EXPECT_EQ(r.status, 201) << "POST /api/auth/join-codes: " << r;
    json j = r.j();
    std::string code = j.is_object() ? jv(j, "code", "") : "";
    if (!code.empty()) secrets().insert(code);
    return {code, j.is_object() ? jv(j, "id", "") : ""};
  }
  Reply join(const std::string& code, const std::string& displayName) {
    Reply r = post("", "/api/auth/join", {{"code", code}, {"display_name", displayName}});
    if (r.status == 201)
      if (std::string t = jv(r.j(), "token", ""); !t.empty()) secrets().insert(t);
    return r;
  }
  // POST /api/sessions as `token`; the id ("" after a failed expectation).
  std::string newSession(const std::string& token, const json& scene = tinyScene()) {
    Reply r = post(token, "/api/sessions", scene);
    EXPECT_EQ(r.status, 201) << "POST /api/sessions: " << r;
    return r.status == 201 ? jv(r.j(), "id", "") : "";
  }
  std::string uploadId(const std::string& token, const std::string& bytes, const std::string& name) {
    Reply r = upload(token, bytes, name);
    EXPECT_EQ(r.status, 201) << "POST /api/assets " << name << ": " << r;
    return r.status == 201 ? jv(r.j(), "id", "") : "";
  }
  // The ids GET /api/sessions lists for `token`.
  std::set<std::string> sessionIds(const std::string& token) const {
    std::set<std::string> ids;
    Reply r = get(token, "/api/sessions");
    EXPECT_EQ(r.status, 200) << r;
    json list = r.j();
    if (list.is_array())
      for (const json& s : list) ids.insert(jv(s, "id", ""));
    return ids;
  }

  // Every secret handed out so far that appears in a file of the data folder or in the log.
  std::vector<std::string> leakedSecrets() const {
    std::vector<std::string> leaks;
    std::vector<std::pair<std::string, std::string>> texts = {{"server log", log()}};
    std::error_code ec;
    for (fs::recursive_directory_iterator it(dataDir, ec), end; !ec && it != end; it.increment(ec)) {
      if (!it->is_regular_file(ec) || it->file_size(ec) > (64u << 20)) continue;
      std::ifstream in(it->path(), std::ios::binary);
      std::ostringstream s;
      s << in.rdbuf();
      texts.emplace_back(it->path().string(), s.str());
    }
    for (const std::string& secret : secrets())
      for (const auto& [where, text] : texts)
        if (text.find(secret) != std::string::npos) leaks.push_back("'" + secret + "' in " + where);
    return leaks;
  }
};

// The checks every answer gets: no CORS header ever; an error is JSON with its code.
void expectWellFormed(const Reply& r, const std::string& what) {
  EXPECT_EQ(corsHeaders(r), "") << what;
  if (r.status == 401) {
    EXPECT_EQ(r.error(), "unauthorized") << what << ": " << r;
    EXPECT_EQ(r.header("WWW-Authenticate").rfind("Bearer", 0), 0u)
        << what << ": a 401 names the scheme; WWW-Authenticate: '" << r.header("WWW-Authenticate") << "'";
  } else if (r.status == 403) {
    EXPECT_EQ(r.error(), "forbidden") << what << ": " << r;
  } else if (r.status == 404) {
    EXPECT_EQ(r.error(), "not_found") << what << ": " << r;
  } else if (r.status == 429) {
    EXPECT_EQ(r.error(), "quota_exceeded") << what << ": " << r;
  }
}

// Every string of `j` with each `from` replaced by its `to`.
json normalized(json j, const std::vector<std::pair<std::string, std::string>>& repl) {
  if (j.is_string()) {
    std::string s = j.get<std::string>();
    for (const auto& [from, to] : repl) {
      if (from.empty()) continue;
      for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
        s.replace(at, from.size(), to);
    }
    return s;
  }
  if (j.is_array() || j.is_object())
    for (auto& v : j) v = normalized(v, repl);
  return j;
}

std::string subst(std::string s, const Vars& vars) {
  for (const auto& [name, value] : vars) {
    const std::string key = "{" + name + "}";
    for (size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + value.size()))
      s.replace(at, key.size(), value);
  }
  return s;
}

// Changes `expires*` fields of the stored join code `code` to the past; false when no file
// under <data-dir>/auth holds the code's hash.
bool expireStoredJoinCode(const std::string& dataDir, const std::string& code) {
  const std::string digest = sha256Hex(code);
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dataDir + "/auth", ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    std::ifstream in(it->path(), std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    if (it->path().filename().string().find(digest) == std::string::npos && s.str().find(digest) == std::string::npos)
      continue;
    json j = json::parse(s.str(), nullptr, false);
    if (!j.is_object()) continue;
    bool changed = false;
    for (auto& [key, value] : j.items()) {
      if (key.find("expire") == std::string::npos) continue;
      if (value.is_string()) value = "2000-01-01T00:00:00Z", changed = true;
      if (value.is_number()) value = 946684800, changed = true;
    }
    if (!changed) continue;
    std::ofstream(it->path(), std::ios::binary | std::ios::trunc) << j.dump();
    return true;
  }
  return false;
}

// A server this test starts by hand (its host, its exit status and its whole output matter).
struct Spawned {
  pid_t pid = -1;
  int outFd = -1;
  std::string dir, logPath;
  ~Spawned() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
    if (outFd >= 0) ::close(outFd);
    std::error_code ec;
    if (!dir.empty()) fs::remove_all(dir, ec);
  }
  bool start(std::vector<std::string> flags) {
    char tmpl[] = "/tmp/brdfa-auth-mode-XXXXXX";
    if (!::mkdtemp(tmpl)) return false;
    dir = tmpl;
    logPath = dir + "/server.log";
    std::vector<std::string> args = {
        BRDFA_SERVER_BINARY, "--port",         "0", "--root", BRDFA_SOURCE_DIR, "--data-dir",
        dir + "/data",       "--idle-timeout", "3"};
    args.insert(args.end(), flags.begin(), flags.end());
    pid = brdfa::testsupport::spawnLogged(std::move(args), logPath, outFd, {"BRDFA_ADMIN_TOKEN"});
    return pid > 0;
  }
  // The exit status once it exits within `timeout`; -1 if it is still running then.
  int waitExit(std::chrono::seconds timeout) {
    for (auto deadline = Clock::now() + timeout; Clock::now() < deadline;) {
      int status = 0;
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        pid = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return -1;
  }
  // The port of its `listening on http://HOST:PORT` line (0 when none came).
  int listeningPort(std::chrono::seconds timeout) {
    std::string line;
    for (auto deadline = Clock::now() + timeout; Clock::now() < deadline;) {
      pollfd p{outFd, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char c;
      if (::read(outFd, &c, 1) <= 0) return 0;
      if (c != '\n') {
        line += c;
        continue;
      }
      std::smatch m;
      if (std::regex_search(line, m, std::regex("listening on http://[^ ]*:([0-9]+)"))) return std::stoi(m[1]);
      line.clear();
    }
    return 0;
  }
  std::string log() const {
    std::ifstream in(logPath, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
};

// ---- Suites ----------------------------------------------------------------------------------

// A suite sharing one `tokens` server with the teacher, alice (made by the teacher) and bob
// (joined with a code).
template <class Flags>
class AuthSuite : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    srv_ = new TestServer;
    srv_->startError = srv_->startTokens(Flags::flags());
    if (!srv_->startError.empty()) return;
    T = srv_->adminToken;
    A = srv_->newStudent("alice", "Alice A.");
    auto [code, id] = srv_->newJoinCode();
    Reply joined = srv_->join(code, "Bob");
    EXPECT_EQ(joined.status, 201) << joined;
    EXPECT_EQ(jv(joined.j(), "user", ""), "bob") << joined;
    B = jv(joined.j(), "token", "");
    if (A.empty() || B.empty()) srv_->startError = "could not make the students alice and bob";
  }
  static void TearDownTestSuite() {
    if (srv_ && srv_->proc.running()) {
      const int code = srv_->proc.terminate();
      EXPECT_EQ(code, 0) << "server did not stop cleanly; log:\n" << srv_->proc.logTail();
    }
    delete srv_;
    srv_ = nullptr;
  }
  void SetUp() override {
    ASSERT_TRUE(srv_ && srv_->proc.running() && srv_->startError.empty())
        << "server did not start: " << (srv_ ? srv_->startError : "");
  }
  void TearDown() override {
    if (!srv_ || !srv_->proc.running()) return;
    Reply health = srv_->get("", "/api/health");
    EXPECT_EQ(health.status, 200) << "server unhealthy after the test: " << health;
    for (const std::string& leak : srv_->leakedSecrets()) ADD_FAILURE() << "a secret is stored or logged: " << leak;
    if (HasFailure()) std::fprintf(stderr, "---- server log tail ----\n%s\n", srv_->proc.logTail(4000).c_str());
  }

  static inline TestServer* srv_ = nullptr;
  static inline std::string T, A, B;  // the teacher's, alice's and bob's tokens
};

struct RoomyFlags {
  static std::vector<std::string> flags() {
    return {"--quota-sessions", "20", "--quota-jobs", "20", "--quota-renders", "4", "--quota-uploads", "50"};
  }
};

// ---- The matrix ------------------------------------------------------------------------------

class AuthMatrix : public AuthSuite<RoomyFlags> {
 protected:
  static void SetUpTestSuite() {
    AuthSuite::SetUpTestSuite();
    if (!srv_->startError.empty()) return;
    // `default` gets a tiny scene, so reading it costs nothing.
    Reply r = srv_->call(T, "PUT", "/api/sessions/default/scene", tinyScene().dump());
    EXPECT_EQ(r.status, 200) << r;
  }
};

enum Who { kOwner, kOther, kTeacher, kAnon };
const char* const kWhoName[] = {"owner (alice)", "other student (bob)", "teacher", "no token"};
using Codes = std::vector<int>;  // the statuses a cell accepts; empty: any (the spec leaves it open)

// What each caller may get, by Who.
struct Expect {
  Codes owner, other, teacher, anon;
  const Codes& of(Who w) const { return w == kOwner ? owner : w == kOther ? other : w == kTeacher ? teacher : anon; }
};

struct Row {
  std::string method, path, body;
  Expect expect;
  // Variables ("NAME", or "NAME=fake") that a request naming something that does not exist
  // replaces with fake values (kFake's, or the one given): where a student's cell may answer
  // 404, that request must answer the same, body and all.
  std::vector<std::string> hide = {};
  std::string type = "application/json";
  enum Kind { Plain, Raw, Upload } kind = Plain;
  std::function<Vars(Who)> fresh = nullptr;                // per-cell variables (a thing to delete)
  std::function<void(Who, const Reply&)> after = nullptr;  // cleanup after a cell
};

// What the fake (nonexistent) counterpart of each variable is.
const Vars kFake = {{"S", "00000000deadbeef"}, {"BS", "00000000deadbeef"}, {"TS", "00000000deadbeef"},
                    {"X", "00000000deadbeef"}, {"B", "alice/nope"},        {"U", "env_00000000deadbeef"},
                    {"J", "job-999999"},       {"P", "nopreset"},          {"PA", "nopreset"},
                    {"BX", "bob/nope"}};

TEST_F(AuthMatrix, EveryRouteForOwnerOtherStudentTeacherAndNobody) {
  TestServer& s = *srv_;
  const std::string lambert = kLambertWhite;
  const std::array<std::string, 4> tok = {A, B, T, ""};

  // ---- alice's things, and a few of bob's and the teacher's --------------------------------
  Reply created = s.post(A, "/api/sessions", tinyScene());
  ASSERT_EQ(created.status, 201) << created;
  Vars v;
  v["S"] = jv(created.j(), "id", "");
  v["K"] = jv(created.j(), "view_key", "");
  EXPECT_FALSE(v["K"].empty()) << "POST /api/sessions answers the view_key: " << created;
  {
    Reply f = s.get(A, "/api/sessions/" + v["S"] + "/frame?min_spp=8&format=pfm");
    EXPECT_EQ(f.status, 200) << f;
  }
  v["BS"] = s.newSession(B);
  {
    Reply f = s.get(B, "/api/sessions/" + v["BS"] + "/frame?min_spp=8&format=pfm");
    EXPECT_EQ(f.status, 200) << f;
  }
  v["TS"] = s.newSession(T);
  v["B"] = "alice/m1";
  v["BX"] = "bob/x";
  Reply put = s.call(A, "PUT", "/api/brdfs/alice/m1", lambert, "text/plain");
  ASSERT_EQ(put.status, 201) << put;
  put = s.call(A, "PUT", "/api/brdfs/alice/m1/presets/p1_alice", R"({"Kd": [0.5, 0.5, 0.5]})");
  ASSERT_EQ(put.status, 201) << put;
  v["P"] = "p1_alice";
  put = s.call(A, "PUT", "/api/brdfs/ggx/presets/pa_alice", R"({"roughness": 0.4})");
  ASSERT_EQ(put.status, 201) << put;
  v["PA"] = "pa_alice";
  put = s.call(T, "PUT", "/api/brdfs/course1", lambert, "text/plain");
  ASSERT_EQ(put.status, 201) << put;
  v["U"] = s.uploadId(A, hdrFile(), "alice-sky.hdr");
  v["TU"] = s.uploadId(T, hdrFile(), "course-sky.hdr");
  v["JC"] = s.newJoinCode().second;
  Reply second = s.post(T, "/api/auth/users/alice/tokens", json::object());
  ASSERT_EQ(second.status, 201) << second;
  const std::string aliceSecond = jv(second.j(), "token", "");
  secrets().insert(aliceSecond);
  v["A2"] = jv(second.j(), "token_id", "");
  s.newStudent("victim0");
  ASSERT_FALSE(v["S"].empty() || v["BS"].empty() || v["TS"].empty() || v["U"].empty() || v["TU"].empty());

  const json sceneBefore = s.get(A, "/api/sessions/" + v["S"] + "/scene").j();
  const std::string tiny = tinyScene().dump();

  // Per-cell things to delete: owner and teacher get a fresh one each; the others try alice's.
  auto freshFor = [&](std::function<std::string(Who)> make, const std::string& otherwise) {
    return [make, otherwise, &v](Who w) -> Vars {
      return {{"X", (w == kOwner || w == kTeacher) ? make(w) : v[otherwise]}};
    };
  };
  int counter = 0;
  // A preset of alice's to delete: a fresh one for those who may, her p1 for the others.
  auto freshPreset = [&](Who w) -> Vars {
    if (w == kOther || w == kAnon) return {{"X", v["P"]}};
    const std::string name = "pdel" + std::to_string(++counter);
    Reply r = s.call(A, "PUT", "/api/brdfs/alice/m1/presets/" + name, "{}");
    EXPECT_EQ(r.status, 201) << r;
    return {{"X", name}};
  };
  // A created thing is deleted again by whoever made it.
  auto deleteCreated = [&](const std::string& prefix) {
    return [&s, &tok, prefix](Who w, const Reply& r) {
      if (r.status / 100 == 2 && r.j().is_object() && r.j().contains("id"))
        s.call(tok[w], "DELETE", prefix + r.j()["id"].get<std::string>());
    };
  };

  const Codes ok200 = {200}, c201 = {201}, c202 = {202}, c204 = {204}, c401 = {401}, c403 = {403}, c404 = {404};
  std::vector<Row> rows = {
      // Public.
      {"GET", "/api/health", "", {ok200, ok200, ok200, ok200}},
      {"GET", "/api/ready", "", {ok200, ok200, ok200, ok200}},
      {"GET", "/metrics", "", {ok200, ok200, ok200, ok200}},
      {"GET", "/", "", {ok200, ok200, ok200, ok200}},
      {"GET", "/api/no-such-route", "", {c404, c404, c404, {401, 404}}},
      // Who am I, and the teacher's routes.
      {"GET", "/api/auth/me", "", {ok200, ok200, ok200, c401}},
      {"GET", "/api/auth/join-codes", "", {c403, c403, ok200, c401}},
      {"POST",
       "/api/auth/join-codes",
       R"({"ttl_minutes": 5})",
       {c403, c403, c201, c401},
       {},
       "application/json",
       Row::Plain,
       nullptr,
       [](Who, const Reply& r) {
         if (r.status == 201) secrets().insert(jv(r.j(), "code", ""));
       }},
      {"DELETE",
       "/api/auth/join-codes/{X}",
       "",
       {c403, c403, c204, c401},
       {},
       "application/json",
       Row::Plain,
       [&](Who w) -> Vars {
         return {{"X", w == kTeacher ? s.newJoinCode().second : v["JC"]}};
       }},
      {"GET", "/api/auth/users", "", {c403, c403, ok200, c401}},
      {"POST",
       "/api/auth/users",
       R"({"user": "zed", "display_name": "Zed"})",
       {c403, c403, c201, c401},
       {},
       "application/json",
       Row::Plain,
       nullptr,
       [](Who, const Reply& r) {
         if (r.status == 201) secrets().insert(jv(r.j(), "token", ""));
       }},
      {"POST",
       "/api/auth/users/alice/tokens",
       "",
       {c403, c403, c201, c401},
       {},
       "application/json",
       Row::Plain,
       nullptr,
       [](Who, const Reply& r) {
         if (r.status == 201) secrets().insert(jv(r.j(), "token", ""));
       }},
      {"DELETE",
       "/api/auth/users/alice/tokens/{X}",
       "",
       {c403, c403, c204, c401},
       {},
       "application/json",
       Row::Plain,
       [&](Who w) -> Vars {
         if (w != kTeacher) return {{"X", v["A2"]}};
         Reply t = s.post(T, "/api/auth/users/alice/tokens", json::object());
         secrets().insert(jv(t.j(), "token", ""));
         return {{"X", jv(t.j(), "token_id", "")}};
       }},
      {"DELETE",
       "/api/auth/users/{X}",
       "",
       {c403, c403, c204, c401},
       {},
       "application/json",
       Row::Plain,
       [&](Who w) -> Vars {
         if (w != kTeacher) return {{"X", "victim0"}};
         const std::string name = "victim" + std::to_string(++counter);
         s.newStudent(name);
         return {{"X", name}};
       }},
      // The library.
      {"GET", "/api/brdfs", "", {ok200, ok200, ok200, c401}},
      {"GET", "/api/brdfs/ggx", "", {ok200, ok200, ok200, c401}},
      {"PUT", "/api/brdfs/ggx", lambert, {{403, 409}, {403, 409}, {409}, c401}, {}, "text/plain"},
      {"POST", "/api/brdfs/validate", lambert, {ok200, ok200, ok200, c401}, {}, "text/plain"},
      {"GET", "/api/brdfs/{B}", "", {ok200, c404, ok200, c401}, {"B"}},
      {"PUT", "/api/brdfs/{B}", lambert, {ok200, {403, 404}, c403, c401}, {"B"}, "text/plain"},
      {"PATCH", "/api/brdfs/{B}", R"({"shared": false})", {ok200, {403, 404}, c403, c401}, {"B"}},
      {"DELETE",
       "/api/brdfs/{X}",
       "",
       {c204, c404, c204, c401},
       {"X=alice/nope"},
       "application/json",
       Row::Plain,
       freshFor(
           [&](Who) {
             const std::string name = "alice/del" + std::to_string(++counter);
             Reply r = s.call(A, "PUT", "/api/brdfs/" + name, lambert, "text/plain");
             EXPECT_EQ(r.status, 201) << r;
             return name;
           },
           "B")},
      {"GET", "/api/brdfs/{B}/presets", "", {ok200, c404, ok200, c401}, {"B"}},
      // Presets are per person: the teacher's own presets of alice/m1 do not hold alice's p1.
      {"GET", "/api/brdfs/{B}/presets/{P}", "", {ok200, c404, c404, c401}, {"P"}},
      {"GET", "/api/brdfs/{B}/presets/{P}?owner=alice", "", {{}, c404, ok200, c401}, {"B"}},
      {"PUT", "/api/brdfs/{B}/presets/p2", "{}", {c201, c404, c201, c401}, {"B"}},
      {"DELETE",
       "/api/brdfs/{B}/presets/{X}",
       "",
       {c204, c404, c404, c401},
       {"X=nopreset"},
       "application/json",
       Row::Plain,
       freshPreset},
      {"DELETE",
       "/api/brdfs/{B}/presets/{X}?owner=alice",
       "",
       {{}, c404, c204, c401},
       {"B"},
       "application/json",
       Row::Plain,
       freshPreset},
      {"GET", "/api/brdfs/ggx/presets", "", {ok200, ok200, ok200, c401}},
      {"GET", "/api/brdfs/ggx/presets/{PA}", "", {ok200, c404, c404, c401}, {"PA"}},
      {"GET", "/api/brdfs/ggx/presets/{PA}?owner=alice", "", {{}, {}, ok200, c401}},
      // The course library: the teacher's, read by everyone.
      {"GET", "/api/brdfs/course1", "", {ok200, ok200, ok200, c401}},
      {"PUT", "/api/brdfs/course1", lambert, {c403, c403, ok200, c401}, {}, "text/plain"},
      {"DELETE",
       "/api/brdfs/{X}",
       "",
       {c403, c403, c204, c401},
       {},
       "application/json",
       Row::Plain,
       [&](Who w) -> Vars {
         if (w != kTeacher) return {{"X", "course1"}};
         const std::string name = "coursedel" + std::to_string(++counter);
         Reply r = s.call(T, "PUT", "/api/brdfs/" + name, lambert, "text/plain");
         EXPECT_EQ(r.status, 201) << r;
         return {{"X", name}};
       }},
      // A student saves only under their own name.
      {"PUT", "/api/brdfs/barename", lambert, {c403, c403, c201, c401}, {}, "text/plain"},
      {"PUT", "/api/brdfs/{BX}", lambert, {{403, 404}, c201, {}, c401}, {"BX"}, "text/plain"},
      // Sessions.
      {"GET", "/api/sessions", "", {ok200, ok200, ok200, c401}},
      {"POST",
       "/api/sessions",
       tiny,
       {c201, c201, c201, c401},
       {},
       "application/json",
       Row::Plain,
       nullptr,
       deleteCreated("/api/sessions/")},
      {"GET", "/api/sessions/{S}", "", {ok200, c404, ok200, c401}, {"S"}},
      {"GET", "/api/sessions/{S}/scene", "", {ok200, c404, ok200, c401}, {"S"}},
      {"GET", "/api/sessions/{S}/frame?min_spp=0", "", {ok200, c404, ok200, c401}, {"S"}},
      {"GET", "/api/sessions/{S}/frame?min_spp=0&format=pfm", "", {ok200, c404, ok200, c401}, {"S"}},
      {"GET", "/api/sessions/{S}/stats", "", {ok200, c404, ok200, c401}, {"S"}},
      {"GET", "/api/sessions/{S}/convergence", "", {ok200, c404, ok200, c401}, {"S"}},
      {"GET", "/api/sessions/{S}/stream", "", {ok200, c404, ok200, c401}, {"S"}, "", Row::Raw},
      {"GET", "/api/sessions/{S}/difference?against={S}&format=json", "", {ok200, c404, ok200, c401}, {"S"}},
      {"PUT", "/api/sessions/{S}/scene", tiny, {ok200, c404, c403, c401}, {"S"}},
      {"PATCH", "/api/sessions/{S}/scene", "{}", {ok200, c404, c403, c401}, {"S"}, "application/merge-patch+json"},
      {"DELETE",
       "/api/sessions/{X}",
       "",
       {c204, c404, c204, c401},
       {"X"},
       "application/json",
       Row::Plain,
       freshFor([&](Who) { return s.newSession(A); }, "S")},
      {"GET", "/api/sessions/{BS}", "", {c404, ok200, ok200, c401}, {"BS"}},
      {"GET", "/api/sessions/{TS}", "", {c404, c404, ok200, c401}, {"TS"}},
      {"GET", "/api/sessions/{S}/difference?against={BS}&format=json", "", {c404, c404, ok200, c401}, {"BS"}},
      // The shared `default` session: everyone reads it, only the teacher changes it.
      {"GET", "/api/sessions/default", "", {ok200, ok200, ok200, c401}},
      {"GET", "/api/sessions/default/frame?min_spp=0", "", {ok200, ok200, ok200, c401}},
      {"PUT", "/api/sessions/default/scene", tiny, {c403, c403, ok200, c401}},
      {"PATCH", "/api/sessions/default/scene", "{}", {c403, c403, ok200, c401}, {}, "application/merge-patch+json"},
      {"DELETE", "/api/sessions/default", "", {{409}, {409}, {409}, c401}},
      // A view key reads frames without a token.
      {"GET", "/api/sessions/{S}/frame?min_spp=0&key={K}", "", {ok200, {}, ok200, ok200}},
      {"GET", "/api/sessions/{S}/frame?min_spp=0&key=0123456789abcdef0123456789abcdef", "", {{}, {}, {}, c401}},
      // One-shot renders and analyses name only what their requester may read.
      {"POST", "/api/render", renderBody(tinyScene()).dump(), {ok200, ok200, ok200, c401}},
      {"POST", "/api/render", renderBody(tinyScene("{B}")).dump(), {ok200, c404, ok200, c401}, {"B"}},
      {"POST", "/api/render", renderBody(tinySceneIn("{U}")).dump(), {ok200, c404, ok200, c401}, {"U"}},
      {"POST", "/api/render", renderBody(tinySceneIn("{TU}")).dump(), {ok200, ok200, ok200, c401}},
      {"POST",
       "/api/analysis/polar",
       R"({"series": [{"brdf": "lambert"}], "resolution": 3})",
       {ok200, ok200, ok200, c401}},
      {"POST",
       "/api/analysis/polar",
       R"({"series": [{"brdf": "{B}"}], "resolution": 3})",
       {ok200, c404, ok200, c401},
       {"B"}},
      {"POST",
       "/api/analysis/lobe",
       R"({"series": [{"brdf": "lambert"}], "resolution": 3})",
       {ok200, ok200, ok200, c401}},
      {"POST",
       "/api/analysis/albedo",
       R"({"series": [{"brdf": "lambert"}], "theta_v": [0], "samples": 2048})",
       {ok200, ok200, ok200, c401}},
      {"POST",
       "/api/analysis/slice",
       R"({"series": [{"brdf": "lambert"}], "resolution": 3})",
       {ok200, ok200, ok200, c401}},
      // A scene names only uploads and BRDFs its session's owner may read.
      {"POST",
       "/api/sessions",
       tinySceneIn("{U}").dump(),
       {c201, c404, c201, c401},
       {"U"},
       "application/json",
       Row::Plain,
       nullptr,
       deleteCreated("/api/sessions/")},
      {"POST",
       "/api/sessions",
       tinyScene("{B}").dump(),
       {c201, c404, c201, c401},
       {"B"},
       "application/json",
       Row::Plain,
       nullptr,
       deleteCreated("/api/sessions/")},
      {"POST",
       "/api/sessions",
       tinySceneIn("{TU}").dump(),
       {c201, c201, c201, c401},
       {},
       "application/json",
       Row::Plain,
       nullptr,
       deleteCreated("/api/sessions/")},
      {"PATCH",
       "/api/sessions/{BS}/scene",
       json{{"environment", {{"name", "{U}"}}}}.dump(),
       {c404, c404, c403, c401},
       {"U"},
       "application/merge-patch+json"},
      // Uploads.
      {"GET", "/api/assets", "", {ok200, ok200, ok200, c401}},
      {"GET", "/api/assets?kind=environment", "", {ok200, ok200, ok200, c401}},
      {"GET", "/api/assets/{U}", "", {ok200, c404, ok200, c401}, {"U"}},
      {"GET", "/api/assets/{TU}", "", {ok200, ok200, ok200, c401}},
      {"POST", "/api/assets", pngFile(8, 8, false), {c201, c201, c201, c401}, {}, "", Row::Upload},
  };
  // Jobs last: alice's job J renders until it is cancelled.
  std::vector<Row> jobRows = {
      {"POST", "/api/jobs/validate", R"({"names": ["lambert"]})", {c202, c202, c202, c401}},
      {"POST", "/api/jobs/validate", R"({"names": ["{B}"]})", {c202, c404, c202, c401}, {"B"}},
      {"POST",
       "/api/jobs/convergence",
       comparison(tinyScene(), false).dump(),
       {c202, c202, c202, c401},
       {},
       "application/json",
       Row::Plain,
       nullptr,
       deleteCreated("/api/jobs/")},
      {"POST",
       "/api/jobs/convergence",
       comparison(tinyScene("{B}"), false).dump(),
       {c202, c404, c202, c401},
       {"B"},
       "application/json",
       Row::Plain,
       nullptr,
       deleteCreated("/api/jobs/")},
      {"POST",
       "/api/jobs/fit",
       R"({"model": {"brdf": "{B}", "fit": {"Kd": null}}, "target": {"brdf": "lambert"}, "max_evaluations": 20})",
       {c202, c404, c202, c401},
       {"B"},
       "application/json",
       Row::Plain,
       nullptr,
       deleteCreated("/api/jobs/")},
      {"POST",
       "/api/jobs/fit",
       R"({"model": {"brdf": "lambert", "fit": {"Kd": null}}, "target": {"brdf": "{B}"}, "max_evaluations": 20})",
       {c202, c404, c202, c401},
       {"B"},
       "application/json",
       Row::Plain,
       nullptr,
       deleteCreated("/api/jobs/")},
      {"GET", "/api/jobs/{J}", "", {ok200, c404, ok200, c401}, {"J"}},
      {"DELETE",
       "/api/jobs/{X}",
       "",
       {ok200, c404, ok200, c401},
       {"X"},
       "application/json",
       Row::Plain,
       freshFor(
           [&](Who) {
             Reply r = s.post(A, "/api/jobs/convergence", comparison(tinyScene(), true));
             EXPECT_EQ(r.status, 202) << r;
             return jv(r.j(), "id", "");
           },
           "J")},
  };

  // ---- run every cell: nobody, the other student, the teacher, then the owner --------------
  auto runCell = [&](const Row& row, Who w, const Vars& vars) -> Reply {
    const std::string path = subst(row.path, vars);
    const std::string body = subst(row.body, vars);
    if (row.kind == Row::Raw) return rawRequest(s.port(), row.method, path, bearer(tok[w]));
    if (row.kind == Row::Upload) return s.upload(tok[w], row.body, "small.png");
    return s.call(tok[w], row.method, path, body, row.type);
  };
  int cells = 0;
  auto runRows = [&](const std::vector<Row>& table) {
    for (const Row& row : table) {
      for (Who w : {kAnon, kOther, kTeacher, kOwner}) {
        Vars vars = v;
        if (row.fresh)
          for (auto& [name, value] : row.fresh(w)) vars[name] = value;
        const std::string what = row.method + " " + subst(row.path, vars) + " as " + kWhoName[w] + " (row " +
                                 row.method + " " + row.path + ")";
        Reply r = runCell(row, w, vars);
        ++cells;
        const Codes& want = row.expect.of(w);
        if (!want.empty()) {
          EXPECT_TRUE(std::find(want.begin(), want.end(), r.status) != want.end())
              << what << ": expected " << json(want).dump() << ", got " << r;
        }
        expectWellFormed(r, what);
        // Someone else's thing answers as one that does not exist.
        const bool mayHide = std::find(want.begin(), want.end(), 404) != want.end();
        if (mayHide && !row.hide.empty() && w != kTeacher && w != kAnon) {
          Vars fake = vars;
          std::vector<std::pair<std::string, std::string>> realToX, fakeToX;
          for (const std::string& name : row.hide) {
            const size_t eq = name.find('=');
            const std::string var = name.substr(0, eq);
            const std::string value = eq == std::string::npos ? kFake.at(var) : name.substr(eq + 1);
            fake[var] = value;
            realToX.emplace_back(vars[var], "<X>");
            fakeToX.emplace_back(value, "<X>");
          }
          Reply m = runCell(row, w, fake);
          EXPECT_EQ(r.status, m.status) << what << " answers " << r << "\nbut for a thing that does not exist: " << m;
          EXPECT_EQ(normalized(r.j(), realToX), normalized(m.j(), fakeToX))
              << what << ": the answer tells that the thing exists\n  real: " << r.body << "\n  none: " << m.body;
        }
        if (row.after) row.after(w, r);
      }
    }
  };
  runRows(rows);

  Reply job = s.post(A, "/api/jobs/convergence", comparison(tinyScene(), true));
  ASSERT_EQ(job.status, 202) << job;
  v["J"] = jv(job.j(), "id", "");
  runRows(jobRows);
  std::fprintf(stderr, "[ matrix ] %zu routes x 4 callers: %d cells\n", rows.size() + jobRows.size(), cells);

  // ---- alice's things after bob's, the teacher's and nobody's requests --------------------
  Reply scene = s.get(A, "/api/sessions/" + v["S"] + "/scene");
  EXPECT_EQ(scene.status, 200) << scene;
  EXPECT_EQ(scene.j(), sceneBefore) << "alice's scene changed";
  Reply brdf = s.get(A, "/api/brdfs/alice/m1");
  EXPECT_EQ(brdf.status, 200) << brdf;
  EXPECT_EQ(jv(brdf.j(), "source", ""), lambert);
  EXPECT_EQ(jv(brdf.j(), "shared", true), false) << brdf;
  EXPECT_EQ(jv(brdf.j(), "owner", ""), "alice") << brdf;
  Reply preset = s.get(A, "/api/brdfs/alice/m1/presets/p1_alice");
  EXPECT_EQ(preset.status, 200) << "alice's preset p1 is gone: " << preset;
  EXPECT_EQ(s.get(A, "/api/brdfs/ggx/presets/pa_alice").status, 200) << "alice's ggx preset is gone";
  EXPECT_EQ(s.get(A, "/api/assets/" + v["U"]).status, 200) << "alice's upload is gone";
  EXPECT_EQ(jv(s.get(T, "/api/brdfs/course1").j(), "source", ""), lambert);
  Reply jobNow = s.get(A, "/api/jobs/" + v["J"]);
  EXPECT_EQ(jobNow.status, 200) << jobNow;
  EXPECT_NE(jv(jobNow.j(), "state", ""), "cancelled") << "bob's or nobody's DELETE cancelled alice's job";
  EXPECT_EQ(s.get(aliceSecond, "/api/auth/me").status, 200) << "a student revoked alice's token";
  EXPECT_EQ(s.get(T, "/api/auth/users").j().dump().find("\"victim0\"") != std::string::npos, true)
      << "a student deleted the user victim0";
  EXPECT_EQ(s.get(B, "/api/brdfs/bob/x").status, 200);
  EXPECT_NE(jv(s.get(T, "/api/brdfs/barename").j(), "owner", "x"), "alice")
      << "a student's PUT of a bare name saved it as theirs";

  // Stop alice's job: it would render for minutes.
  Reply cancel = s.call(A, "DELETE", "/api/jobs/" + v["J"]);
  EXPECT_EQ(cancel.status, 200) << cancel;
  EXPECT_EQ(jv(cancel.j(), "state", ""), "cancelled") << cancel;
}

// GET /api/sessions, /api/brdfs, /api/assets list only what the caller may read; the teacher's
// session list names owners.
TEST_F(AuthMatrix, ListsShowOnlyWhatTheCallerMayRead) {
  TestServer& s = *srv_;
  const std::string as = s.newSession(A), bs = s.newSession(B), ts = s.newSession(T);
  ASSERT_FALSE(as.empty() || bs.empty() || ts.empty());

  std::set<std::string> alices = s.sessionIds(A), bobs = s.sessionIds(B), teachers = s.sessionIds(T);
  EXPECT_TRUE(alices.count(as));
  EXPECT_FALSE(alices.count(bs) || alices.count(ts)) << "alice lists others' sessions";
  EXPECT_TRUE(bobs.count(bs));
  EXPECT_FALSE(bobs.count(as) || bobs.count(ts)) << "bob lists others' sessions";
  EXPECT_TRUE(teachers.count(as) && teachers.count(bs) && teachers.count(ts)) << "the teacher lists every session";

  for (const json& entry : s.get(A, "/api/sessions").j())
    if (jv(entry, "id", "") == as) {
      EXPECT_FALSE(jv(entry, "view_key", "").empty()) << entry.dump();
    }
  for (const json& entry : s.get(T, "/api/sessions").j()) {
    if (jv(entry, "id", "") == as) {
      EXPECT_EQ(jv(entry, "owner", ""), "alice") << entry.dump();
      EXPECT_EQ(jv(entry, "owner_display_name", ""), "Alice A.") << entry.dump();
    }
    if (jv(entry, "id", "") == bs) {
      EXPECT_EQ(jv(entry, "owner", ""), "bob") << entry.dump();
      EXPECT_EQ(jv(entry, "owner_display_name", ""), "Bob") << entry.dump();
    }
  }
  Reply one = s.get(A, "/api/sessions/" + as);
  EXPECT_FALSE(jv(one.j(), "view_key", "").empty()) << "GET /api/sessions/{id} answers the view_key: " << one;

  // BRDFs: alice's own are listed for her and the teacher, not for bob.
  ASSERT_EQ(s.call(A, "PUT", "/api/brdfs/alice/listed", kLambertWhite, "text/plain").status, 201);
  auto names = [&](const std::string& token) {
    std::set<std::string> out;
    for (const json& b : s.get(token, "/api/brdfs").j()) out.insert(jv(b, "name", ""));
    return out;
  };
  EXPECT_TRUE(names(A).count("alice/listed"));
  EXPECT_TRUE(names(T).count("alice/listed"));
  EXPECT_FALSE(names(B).count("alice/listed")) << "bob lists alice's unshared BRDF";
  EXPECT_TRUE(names(B).count("ggx"));

  // Uploads: alice's is listed for her and the teacher, not for bob; the teacher's for all.
  const std::string au = s.uploadId(A, pngFile(8, 8, false), "alice.png");
  const std::string tu = s.uploadId(T, pngFile(8, 8, false), "course.png");
  auto assets = [&](const std::string& token) {
    std::set<std::string> out;
    for (const json& a : s.get(token, "/api/assets").j()) out.insert(jv(a, "id", ""));
    return out;
  };
  EXPECT_TRUE(assets(A).count(au) && assets(A).count(tu));
  EXPECT_TRUE(assets(T).count(au) && assets(T).count(tu));
  EXPECT_FALSE(assets(B).count(au)) << "bob lists alice's upload";
  EXPECT_TRUE(assets(B).count(tu)) << "the teacher's uploads are course assets";

  for (const auto& [token, id] : std::vector<std::pair<std::string, std::string>>{{A, as}, {B, bs}, {T, ts}})
    EXPECT_EQ(s.call(token, "DELETE", "/api/sessions/" + id).status, 204);
  EXPECT_EQ(s.call(A, "DELETE", "/api/brdfs/alice/listed").status, 204);
}

// The course library, a student's namespace, sharing, and the teacher reading presets.
TEST_F(AuthMatrix, CourseBrdfsNamespacesAndSharing) {
  TestServer& s = *srv_;
  const std::string lambert = kLambertWhite;
  ASSERT_EQ(s.call(T, "PUT", "/api/brdfs/course_ggx", lambert, "text/plain").status, 201);
  Reply course = s.get(A, "/api/brdfs/course_ggx");
  EXPECT_EQ(course.status, 200) << course;
  EXPECT_TRUE(course.j().contains("owner") && course.j()["owner"].is_null())
      << "a course BRDF has owner null: " << course;
  EXPECT_EQ(s.call(A, "PUT", "/api/brdfs/course_ggx", lambert, "text/plain").status, 403);
  EXPECT_EQ(s.call(A, "DELETE", "/api/brdfs/course_ggx").status, 403);

  // A bare name is the course's: a student's PUT is 403 and names where to save.
  Reply bare = s.call(A, "PUT", "/api/brdfs/my_ggx", lambert, "text/plain");
  EXPECT_EQ(bare.status, 403) << bare;
  EXPECT_NE(jv(bare.j(), "message", "").find("alice/my_ggx"), std::string::npos)
      << "the 403 names the right name: " << bare;
  EXPECT_EQ(s.get(A, "/api/brdfs/my_ggx").status, 404) << "nothing was saved";

  // Sharing.
  Reply saved = s.call(A, "PUT", "/api/brdfs/alice/sh", lambert, "text/plain");
  ASSERT_EQ(saved.status, 201) << saved;
  EXPECT_EQ(jv(saved.j(), "owner", ""), "alice") << saved;
  EXPECT_EQ(jv(saved.j(), "shared", true), false) << saved;
  EXPECT_EQ(s.get(B, "/api/brdfs/alice/sh").status, 404);
  EXPECT_EQ(s.call(B, "PATCH", "/api/brdfs/alice/sh", R"({"shared": true})").status, 404)
      << "bob cannot share what he cannot see";
  Reply shared = s.call(A, "PATCH", "/api/brdfs/alice/sh", R"({"shared": true})");
  EXPECT_EQ(shared.status, 200) << shared;
  Reply seen = s.get(B, "/api/brdfs/alice/sh");
  EXPECT_EQ(seen.status, 200) << seen;
  EXPECT_EQ(jv(seen.j(), "shared", false), true) << seen;
  EXPECT_EQ(jv(seen.j(), "source", ""), lambert);
  bool listed = false;
  for (const json& b : s.get(B, "/api/brdfs").j()) listed |= jv(b, "name", "") == "alice/sh";
  EXPECT_TRUE(listed) << "a shared BRDF is listed for bob";
  EXPECT_EQ(s.call(B, "PUT", "/api/brdfs/alice/sh", lambert, "text/plain").status, 403);
  EXPECT_EQ(s.call(B, "DELETE", "/api/brdfs/alice/sh").status, 403);
  EXPECT_EQ(s.call(B, "PATCH", "/api/brdfs/alice/sh", R"({"shared": false})").status, 403);
  // Bob may use it in his scenes while it is shared.
  const std::string bs = s.newSession(B, tinyScene("alice/sh"));
  EXPECT_EQ(s.post(B, "/api/render", renderBody(tinyScene("alice/sh"))).status, 200);
  Reply unshared = s.call(A, "PATCH", "/api/brdfs/alice/sh", R"({"shared": false})");
  EXPECT_EQ(unshared.status, 200) << unshared;
  EXPECT_EQ(s.get(B, "/api/brdfs/alice/sh").status, 404) << "un-shared: bob no longer reads it";
  EXPECT_EQ(s.post(B, "/api/render", renderBody(tinyScene("alice/sh"))).status, 404);
  if (!bs.empty()) {
    EXPECT_EQ(s.call(B, "DELETE", "/api/sessions/" + bs).status, 204);
  }

  // Presets are per person; the teacher reads a student's with ?owner=.
  ASSERT_EQ(s.call(A, "PUT", "/api/brdfs/alice/sh/presets/warm", R"({"Kd": [0.9, 0.5, 0.2]})").status, 201);
  ASSERT_EQ(s.call(A, "PUT", "/api/brdfs/ggx/presets/shiny", R"({"roughness": 0.05})").status, 201);
  Reply list = s.get(T, "/api/brdfs/alice/sh/presets?owner=alice");
  EXPECT_EQ(list.status, 200) << list;
  EXPECT_EQ(list.j(), json::array({"warm"})) << list;
  Reply one = s.get(T, "/api/brdfs/alice/sh/presets/warm?owner=alice");
  EXPECT_EQ(one.status, 200) << one;
  EXPECT_EQ(one.j(), json::parse(R"({"Kd": [0.9, 0.5, 0.2]})")) << one;
  EXPECT_EQ(s.get(T, "/api/brdfs/alice/sh/presets").j(), json::array()) << "the teacher's own presets are apart";
  Reply bobs = s.get(B, "/api/brdfs/ggx/presets");
  EXPECT_EQ(bobs.status, 200) << bobs;
  EXPECT_EQ(bobs.body.find("shiny"), std::string::npos) << "bob lists alice's preset: " << bobs;
  EXPECT_EQ(s.get(B, "/api/brdfs/ggx/presets/shiny").status, 404);
  Reply alices = s.get(A, "/api/brdfs/ggx/presets");
  EXPECT_NE(alices.body.find("shiny"), std::string::npos) << alices;
  EXPECT_EQ(s.get(T, "/api/brdfs/ggx/presets/shiny?owner=alice").status, 200);
  EXPECT_EQ(s.call(T, "DELETE", "/api/brdfs/ggx/presets/shiny?owner=alice").status, 204);
  EXPECT_EQ(s.get(A, "/api/brdfs/ggx/presets/shiny").status, 404) << "the teacher deleted it";

  // The teacher deletes a student's BRDF.
  EXPECT_EQ(s.call(T, "DELETE", "/api/brdfs/alice/sh").status, 204);
  EXPECT_EQ(s.get(A, "/api/brdfs/alice/sh").status, 404);
}

// A session's view_key reads its frames and stream without a token, and nothing else.
TEST_F(AuthMatrix, ViewKeyReadsFramesOnly) {
  TestServer& s = *srv_;
  Reply created = s.post(A, "/api/sessions", tinyScene());
  ASSERT_EQ(created.status, 201) << created;
  const std::string id = jv(created.j(), "id", ""), key = jv(created.j(), "view_key", "");
  ASSERT_FALSE(key.empty()) << created;
  const std::string bs = s.newSession(B);

  Reply frame = s.get("", "/api/sessions/" + id + "/frame?min_spp=1&key=" + key);
  EXPECT_EQ(frame.status, 200) << frame;
  EXPECT_EQ(frame.header("Content-Type"), "image/png");
  Reply stream = rawRequest(s.port(), "GET", "/api/sessions/" + id + "/stream?key=" + key, {});
  EXPECT_EQ(stream.status, 200) << stream;
  EXPECT_EQ(stream.header("Content-Type").rfind("multipart/x-mixed-replace", 0), 0u) << stream.header("Content-Type");

  std::string wrong = key;
  wrong[0] = wrong[0] == 'a' ? 'b' : 'a';
  for (const std::string& path :
       {"/api/sessions/" + id + "/frame?min_spp=0&key=" + wrong,
        "/api/sessions/" + id + "/frame?min_spp=0&key=", "/api/sessions/" + bs + "/frame?min_spp=0&key=" + key,
        "/api/sessions/" + id + "/scene?key=" + key, "/api/sessions/" + id + "/stats?key=" + key,
        "/api/sessions/" + id + "?key=" + key, "/api/sessions?key=" + key}) {
    Reply r = s.get("", path);
    EXPECT_EQ(r.status, 401) << "GET " << path << ": " << r;
    expectWellFormed(r, "GET " + path);
  }
  Reply wrongStream = rawRequest(s.port(), "GET", "/api/sessions/" + id + "/stream?key=" + wrong, {});
  EXPECT_EQ(wrongStream.status, 401) << wrongStream;
  Reply put = s.call("", "PUT", "/api/sessions/" + id + "/scene?key=" + key, tinyScene().dump());
  EXPECT_EQ(put.status, 401) << put;
  Reply del = s.call("", "DELETE", "/api/sessions/" + id + "?key=" + key);
  EXPECT_EQ(del.status, 401) << del;
  EXPECT_EQ(s.get(A, "/api/sessions/" + id).status, 200) << "the key deleted the session";

  // The key dies with the session.
  ASSERT_EQ(s.call(A, "DELETE", "/api/sessions/" + id).status, 204);
  Reply dead = s.get("", "/api/sessions/" + id + "/frame?min_spp=0&key=" + key);
  EXPECT_TRUE(dead.status == 401 || dead.status == 404) << dead;
  if (!bs.empty()) s.call(B, "DELETE", "/api/sessions/" + bs);
}

// Browser safety: cross-site writes are refused before they do anything; there is no CORS.
TEST_F(AuthMatrix, CrossSiteWritesAreRefusedAndThereIsNoCors) {
  TestServer& s = *srv_;
  const std::string self = "http://127.0.0.1:" + std::to_string(s.port());
  const size_t before = s.sessionIds(T).size();
  const std::string body = tinyScene().dump();

  for (const auto& [name, value] :
       std::vector<std::pair<std::string, std::string>>{{"Origin", "http://evil.example"},
                                                        {"Origin", "null"},
                                                        {"Origin", "http://127.0.0.1:1"},
                                                        {"Origin", "http://localhost:" + std::to_string(s.port())},
                                                        {"Sec-Fetch-Site", "cross-site"}}) {
    Reply r = s.call(A, "POST", "/api/sessions", body, "application/json", {{name, value}});
    EXPECT_EQ(r.status, 403) << name << ": " << value << ": " << r;
    EXPECT_EQ(r.error(), "cross_site") << name << ": " << value << ": " << r;
    EXPECT_EQ(corsHeaders(r), "");
  }
  EXPECT_EQ(s.sessionIds(T).size(), before) << "a refused cross-site request made a session";

  // A cross-site form: text/plain and no token.
  Reply form = s.call("", "POST", "/api/sessions", body, "text/plain", {{"Origin", "http://evil.example"}});
  EXPECT_TRUE(form.status == 401 || form.status == 403) << form;
  Reply formNoOrigin = s.call("", "POST", "/api/sessions", body, "text/plain");
  EXPECT_EQ(formNoOrigin.status, 401) << formNoOrigin;
  EXPECT_EQ(s.sessionIds(T).size(), before) << "a token-less form made a session";

  // The same origin, and a script that sends neither header, are not affected.
  Reply same = s.call(A, "POST", "/api/sessions", body, "application/json", {{"Origin", self}});
  EXPECT_EQ(same.status, 201) << same;
  Reply fetchSame = s.call(A, "POST", "/api/sessions", body, "application/json", {{"Sec-Fetch-Site", "same-origin"}});
  EXPECT_EQ(fetchSame.status, 201) << fetchSame;
  const std::string id = jv(same.j(), "id", "");

  // Other writes from another site change nothing either.
  Reply del = s.call(A, "DELETE", "/api/sessions/" + id, "", "", {{"Origin", "http://evil.example"}});
  EXPECT_EQ(del.status, 403) << del;
  EXPECT_EQ(s.get(A, "/api/sessions/" + id).status, 200) << "a cross-site DELETE removed the session";
  Reply brdf =
      s.call(A, "PUT", "/api/brdfs/alice/evil", kLambertWhite, "text/plain", {{"Sec-Fetch-Site", "cross-site"}});
  EXPECT_EQ(brdf.status, 403) << brdf;
  EXPECT_EQ(s.get(A, "/api/brdfs/alice/evil").status, 404);
  Reply patch = s.call(A, "PATCH", "/api/sessions/" + id + "/scene", R"({"render": {"width": 32}})",
                       "application/merge-patch+json", {{"Origin", "null"}});
  EXPECT_EQ(patch.status, 403) << patch;
  EXPECT_EQ(jv(s.get(A, "/api/sessions/" + id + "/scene").j()["render"], "width", 0), 16);
  // Reads are not state-changing.
  EXPECT_EQ(s.call(A, "GET", "/api/sessions", "", "", {{"Origin", "http://evil.example"}}).status, 200);

  // No CORS anywhere, preflights included.
  const httplib::Headers preflight = {{"Origin", "http://evil.example"},
                                      {"Access-Control-Request-Method", "POST"},
                                      {"Access-Control-Request-Headers", "authorization, content-type"}};
  for (const char* path : {"/api/sessions", "/api/brdfs/ggx", "/api/health", "/", "/api/auth/join"}) {
    Reply r = s.call("", "OPTIONS", path, "", "", preflight);
    EXPECT_EQ(corsHeaders(r), "") << "OPTIONS " << path << ": " << r;
    Reply g = s.call(A, "GET", path, "", "", {{"Origin", "http://evil.example"}});
    EXPECT_EQ(corsHeaders(g), "") << "GET " << path;
  }
  for (const std::string& sid : s.sessionIds(A))
    if (sid != "default") s.call(A, "DELETE", "/api/sessions/" + sid);
}

// ---- Tokens and join codes -------------------------------------------------------------------

class AuthTokens : public AuthSuite<RoomyFlags> {};

TEST_F(AuthTokens, MeDescribesEachCaller) {
  TestServer& s = *srv_;
  Reply me = s.get(A, "/api/auth/me");
  ASSERT_EQ(me.status, 200) << me;
  json j = me.j();
  EXPECT_EQ(jv(j, "mode", ""), "tokens");
  EXPECT_EQ(jv(j, "user", ""), "alice");
  EXPECT_EQ(jv(j, "display_name", ""), "Alice A.");
  EXPECT_EQ(jv(j, "role", ""), "student");
  EXPECT_EQ(jv(j, "namespace", ""), "alice/");
  EXPECT_TRUE(j.contains("quotas") && j["quotas"].is_object()) << me;
  Reply teacher = s.get(T, "/api/auth/me");
  EXPECT_EQ(jv(teacher.j(), "role", ""), "teacher") << teacher;
  EXPECT_EQ(jv(teacher.j(), "user", ""), "teacher") << teacher;
  EXPECT_EQ(jv(teacher.j(), "namespace", "x"), "") << teacher;
  Reply anon = s.get("", "/api/auth/me");
  EXPECT_EQ(anon.status, 401);
  expectWellFormed(anon, "GET /api/auth/me without a token");
  for (const std::string& bad :
       {std::string("brdfa_not-a-real-token-0000000000000000000000"), T + "x", std::string("short")}) {
    Reply r = s.get(bad, "/api/auth/me");
    EXPECT_EQ(r.status, 401) << bad << ": " << r;
  }
  // Tokens look as the spec says.
  EXPECT_TRUE(std::regex_match(A, std::regex("brdfa_[A-Za-z0-9_-]{43}"))) << A;
  EXPECT_TRUE(std::regex_match(B, std::regex("brdfa_[A-Za-z0-9_-]{43}"))) << B;
}

TEST_F(AuthTokens, LogoutAndRevocationEndATokenAtOnce) {
  TestServer& s = *srv_;
  const std::string t1 = s.newStudent("carol", "Carol");
  ASSERT_FALSE(t1.empty());
  Reply more = s.post(T, "/api/auth/users/carol/tokens", json::object());
  ASSERT_EQ(more.status, 201) << more;
  const std::string t2 = jv(more.j(), "token", ""), t2id = jv(more.j(), "token_id", "");
  secrets().insert(t2);
  ASSERT_FALSE(t2.empty() || t2id.empty()) << more;
  EXPECT_NE(t1, t2);
  EXPECT_EQ(jv(s.get(t1, "/api/auth/me").j(), "user", ""), "carol");
  EXPECT_EQ(jv(s.get(t2, "/api/auth/me").j(), "user", ""), "carol");

  // The user list shows token ids, never tokens.
  Reply users = s.get(T, "/api/auth/users");
  ASSERT_EQ(users.status, 200) << users;
  EXPECT_EQ(users.body.find(t1), std::string::npos);
  EXPECT_EQ(users.body.find(t2), std::string::npos);
  bool found = false;
  for (const json& u : users.j())
    if (jv(u, "user", "") == "carol") {
      found = true;
      EXPECT_EQ(jv(u, "role", ""), "student");
      EXPECT_EQ(jv(u, "display_name", ""), "Carol");
      const json tokens = field(u, "tokens");
      EXPECT_EQ(tokens.size(), 2u) << u.dump();
      bool hasId = false;
      for (const json& t : tokens) hasId |= jv(t, "id", "") == t2id;
      EXPECT_TRUE(hasId) << u.dump();
    }
  EXPECT_TRUE(found) << users;

  // Logout revokes the token that asked, only that one.
  Reply out = s.call(t1, "POST", "/api/auth/logout");
  EXPECT_EQ(out.status, 204) << out;
  Reply after = s.get(t1, "/api/auth/me");
  EXPECT_EQ(after.status, 401) << after;
  expectWellFormed(after, "a logged-out token");
  EXPECT_EQ(s.post(t1, "/api/sessions", tinyScene()).status, 401);
  EXPECT_EQ(s.get(t2, "/api/auth/me").status, 200) << "logout revoked another token";

  // The teacher revokes a token by its id.
  Reply revoke = s.call(T, "DELETE", "/api/auth/users/carol/tokens/" + t2id);
  EXPECT_EQ(revoke.status, 204) << revoke;
  EXPECT_EQ(s.get(t2, "/api/auth/me").status, 401);
  EXPECT_EQ(s.call(T, "DELETE", "/api/auth/users/carol/tokens/" + t2id).status, 404);
  EXPECT_EQ(s.call(T, "DELETE", "/api/auth/users/carol/tokens/0000000000000000").status, 404);
  EXPECT_EQ(s.post(T, "/api/auth/users/nobody-here/tokens", json::object()).status, 404);

  // Deleting a user revokes every token of theirs.
  const std::string d1 = s.newStudent("dave");
  Reply d2 = s.post(T, "/api/auth/users/dave/tokens", json::object());
  secrets().insert(jv(d2.j(), "token", ""));
  EXPECT_EQ(s.call(T, "DELETE", "/api/auth/users/dave").status, 204);
  EXPECT_EQ(s.get(d1, "/api/auth/me").status, 401);
  EXPECT_EQ(s.get(jv(d2.j(), "token", ""), "/api/auth/me").status, 401);
  EXPECT_EQ(s.call(T, "DELETE", "/api/auth/users/dave").status, 404);

  // Names are unique and valid.
  EXPECT_EQ(s.post(T, "/api/auth/users", {{"user", "carol"}}).status, 409);
  EXPECT_EQ(s.post(T, "/api/auth/users", {{"user", "Not Valid"}}).status, 400);
  EXPECT_EQ(s.post(T, "/api/auth/users", {{"user", "-leading"}}).status, 400);
  // Logging out needs someone to log out; the teacher's token is untouched by all of this.
  EXPECT_EQ(s.call("", "POST", "/api/auth/logout").status, 401);
  EXPECT_EQ(s.get(T, "/api/auth/me").status, 200);
}

TEST_F(AuthTokens, JoinCodesMakeStudentsUntilDeletedOrExpired) {
  TestServer& s = *srv_;
  Reply made = s.post(T, "/api/auth/join-codes", {{"ttl_minutes", 60}});
  ASSERT_EQ(made.status, 201) << made;
  const json code = made.j();
  const std::string c = jv(code, "code", ""), id = jv(code, "id", "");
  secrets().insert(c);
  EXPECT_TRUE(std::regex_match(c, std::regex("[a-z0-9]{16}"))) << c;
  EXPECT_EQ(jv(code, "join_path", ""), "/?join=" + c);
  EXPECT_FALSE(jv(code, "expires_at", "").empty());

  Reply listed = s.get(T, "/api/auth/join-codes");
  ASSERT_EQ(listed.status, 200) << listed;
  EXPECT_EQ(listed.body.find(c), std::string::npos) << "the list shows a code";
  bool hasId = false;
  for (const json& j : listed.j()) hasId |= jv(j, "id", "") == id;
  EXPECT_TRUE(hasId) << listed;

  // Joining makes a user name from the display name.
  Reply first = s.join(c, "Dana Smith");
  ASSERT_EQ(first.status, 201) << first;
  EXPECT_EQ(jv(first.j(), "user", ""), "dana-smith");
  EXPECT_EQ(jv(first.j(), "role", ""), "student");
  EXPECT_EQ(jv(first.j(), "display_name", ""), "Dana Smith");
  Reply again = s.join(c, "Dana Smith");
  ASSERT_EQ(again.status, 201) << again;
  EXPECT_EQ(jv(again.j(), "user", ""), "dana-smith-2");
  Reply me = s.get(jv(first.j(), "token", ""), "/api/auth/me");
  EXPECT_EQ(jv(me.j(), "user", ""), "dana-smith") << me;
  EXPECT_EQ(s.join(c, "").status, 400);
  // Display names are up to 64 characters: a longer one is refused or cut.
  Reply longName = s.join(c, std::string(65, 'x'));
  EXPECT_TRUE(longName.status == 400 || (longName.status == 201 && jv(longName.j(), "display_name", "").size() <= 64))
      << longName;
  EXPECT_EQ(s.join("zzzzzzzzzzzzzzzz", "Eve").status, 404);
  EXPECT_EQ(s.post(T, "/api/auth/join-codes", {{"ttl_minutes", 0}}).status, 400);
  EXPECT_EQ(s.post(T, "/api/auth/join-codes", {{"ttl_minutes", 10081}}).status, 400);

  // Deleted: the code joins nobody.
  EXPECT_EQ(s.call(T, "DELETE", "/api/auth/join-codes/" + id).status, 204);
  Reply deleted = s.join(c, "Frank");
  EXPECT_EQ(deleted.status, 404) << deleted;
  EXPECT_EQ(s.call(T, "DELETE", "/api/auth/join-codes/" + id).status, 404);

  // Expired: the stored code's expiry moved to the past.
  auto [old, oldId] = s.newJoinCode(60);
  ASSERT_FALSE(old.empty());
  ASSERT_TRUE(expireStoredJoinCode(s.dataDir, old)) << "no file under <data-dir>/auth holds the code's SHA-256";
  Reply expired = s.join(old, "Gina");
  EXPECT_EQ(expired.status, 404) << expired;
  EXPECT_EQ(expired.error(), "not_found") << expired;
}

TEST_F(AuthTokens, TokensAreStoredOnlyAsHashes) {
  TestServer& s = *srv_;
  const std::string t = s.newStudent("hash-check");
  ASSERT_FALSE(t.empty());
  const std::string digest = sha256Hex(t);
  ASSERT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  bool stored = false;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(s.dataDir + "/auth/tokens", ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    std::ifstream in(it->path(), std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    stored |= it->path().filename().string().find(digest) != std::string::npos ||
              text.str().find(digest) != std::string::npos;
  }
  EXPECT_TRUE(stored) << "no file under <data-dir>/auth/tokens/ holds the token's SHA-256";
  // TearDown checks that no token or code is in a file of the data folder or in the log.
}

// ---- Quotas ----------------------------------------------------------------------------------

// Upload sizes: a small PNG and a large one; alice's quota of bytes holds the large one alone
// but not both.
const std::string& smallPng() {
  static const std::string png = pngFile(8, 8, false);
  return png;
}
const std::string& largePng() {
  static const std::string png = pngFile(32, 32, true);
  return png;
}

struct TightFlags {
  static std::vector<std::string> flags() {
    return {"--quota-sessions", "2", "--quota-brdfs",        "3",
            "--quota-uploads",  "2", "--quota-upload-bytes", std::to_string(largePng().size() + smallPng().size() / 2),
            "--quota-jobs",     "1", "--quota-renders",      "1"};
  }
};

class AuthQuotas : public AuthSuite<TightFlags> {
 protected:
  // A 429 naming `quota`, with its limit and what is used.
  static void expectQuota(const Reply& r, const std::string& quota, long long limit, const std::string& what) {
    EXPECT_EQ(r.status, 429) << what << ": " << r;
    json j = r.j();
    EXPECT_EQ(r.error(), "quota_exceeded") << what << ": " << r;
    EXPECT_EQ(jv(j, "quota", ""), quota) << what << ": " << r;
    EXPECT_EQ(jv(j, "limit", -1LL), limit) << what << ": " << r;
    EXPECT_TRUE(j.contains("used") && j["used"].is_number()) << what << ": " << r;
    EXPECT_FALSE(jv(j, "message", "").empty()) << what << ": " << r;
    EXPECT_EQ(corsHeaders(r), "");
  }
};

TEST_F(AuthQuotas, Sessions) {
  TestServer& s = *srv_;
  const std::string a = s.newStudent("qs-alice"), b = s.newStudent("qs-bob");
  std::vector<std::pair<std::string, std::string>> made;
  for (int i = 0; i < 2; ++i) made.emplace_back(a, s.newSession(a));
  Reply over = s.post(a, "/api/sessions", tinyScene());
  expectQuota(over, "sessions", 2, "alice's third session");
  EXPECT_EQ(jv(over.j(), "used", -1), 2);
  EXPECT_EQ(s.sessionIds(a).size() - s.sessionIds(a).count("default"), 2u) << "the refused session exists";
  made.emplace_back(b, s.newSession(b));                              // bob is not affected
  for (int i = 0; i < 3; ++i) made.emplace_back(T, s.newSession(T));  // nor the teacher, who has no quota
  // Deleting one frees room.
  ASSERT_EQ(s.call(a, "DELETE", "/api/sessions/" + made[0].second).status, 204);
  made[0].second = s.newSession(a);
  for (const auto& [token, id] : made)
    if (!id.empty()) {
      EXPECT_EQ(s.call(token, "DELETE", "/api/sessions/" + id).status, 204);
    }
}

TEST_F(AuthQuotas, Brdfs) {
  TestServer& s = *srv_;
  const std::string a = s.newStudent("qb-alice"), b = s.newStudent("qb-bob");
  for (int i = 1; i <= 3; ++i) {
    Reply r = s.call(a, "PUT", "/api/brdfs/qb-alice/m" + std::to_string(i), kLambertWhite, "text/plain");
    EXPECT_EQ(r.status, 201) << r;
  }
  Reply over = s.call(a, "PUT", "/api/brdfs/qb-alice/m4", kLambertWhite, "text/plain");
  expectQuota(over, "brdfs", 3, "alice's fourth BRDF");
  EXPECT_EQ(s.get(a, "/api/brdfs/qb-alice/m4").status, 404) << "the refused BRDF was saved";
  Reply replace = s.call(a, "PUT", "/api/brdfs/qb-alice/m1", kLambertWhite, "text/plain");
  EXPECT_EQ(replace.status, 200) << "replacing one adds none: " << replace;
  Reply bobs = s.call(b, "PUT", "/api/brdfs/qb-bob/m1", kLambertWhite, "text/plain");
  EXPECT_EQ(bobs.status, 201) << bobs;
  Reply course = s.call(T, "PUT", "/api/brdfs/qb_course", kLambertWhite, "text/plain");
  EXPECT_EQ(course.status, 201) << course;
  EXPECT_EQ(s.call(a, "DELETE", "/api/brdfs/qb-alice/m1").status, 204);
  EXPECT_EQ(s.call(a, "PUT", "/api/brdfs/qb-alice/m4", kLambertWhite, "text/plain").status, 201);
}

TEST_F(AuthQuotas, UploadsAndUploadBytes) {
  TestServer& s = *srv_;
  const std::string a = s.newStudent("qu-alice"), b = s.newStudent("qu-bob");
  const long long byteLimit = static_cast<long long>(largePng().size() + smallPng().size() / 2);
  EXPECT_EQ(s.upload(a, smallPng(), "1.png").status, 201);
  Reply tooBig = s.upload(a, largePng(), "big.png");
  expectQuota(tooBig, "upload_bytes", byteLimit, "alice's upload past her bytes");
  EXPECT_LE(jv(tooBig.j(), "used", 0LL), byteLimit) << tooBig;
  EXPECT_EQ(s.upload(a, smallPng(), "2.png").status, 201);
  Reply tooMany = s.upload(a, smallPng(), "3.png");
  expectQuota(tooMany, "uploads", 2, "alice's third upload");
  EXPECT_EQ(jv(tooMany.j(), "used", -1), 2) << tooMany;
  int alices = 0;
  for (const json& asset : s.get(a, "/api/assets").j()) alices += jv(asset, "builtin", true) ? 0 : 1;
  EXPECT_EQ(alices, 2) << "a refused upload was kept";
  EXPECT_EQ(s.upload(b, largePng(), "big.png").status, 201) << "bob is not affected";
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(s.upload(T, largePng(), "course.png").status, 201) << "the teacher has no quota";
}

TEST_F(AuthQuotas, Jobs) {
  TestServer& s = *srv_;
  const std::string a = s.newStudent("qj-alice"), b = s.newStudent("qj-bob");
  std::vector<std::pair<std::string, std::string>> jobs;
  Reply first = s.post(a, "/api/jobs/convergence", comparison(tinyScene(), true));
  ASSERT_EQ(first.status, 202) << first;
  jobs.emplace_back(a, jv(first.j(), "id", ""));
  expectQuota(s.post(a, "/api/jobs/convergence", comparison(tinyScene(), true)), "jobs", 1, "alice's second job");
  expectQuota(s.post(a, "/api/jobs/validate", {{"names", {"lambert"}}}), "jobs", 1, "alice's validation job");
  Reply bobs = s.post(b, "/api/jobs/convergence", comparison(tinyScene(), true));
  EXPECT_EQ(bobs.status, 202) << "bob is not affected: " << bobs;
  jobs.emplace_back(b, jv(bobs.j(), "id", ""));
  // Cancelling frees room: at once for a queued job (bob's waits behind alice's, comparisons
  // run one at a time)...
  Reply bobCancelled = s.call(b, "DELETE", "/api/jobs/" + jobs[1].second);
  EXPECT_EQ(jv(bobCancelled.j(), "state", ""), "cancelled") << bobCancelled;
  Reply bobAgain = s.post(b, "/api/jobs/validate", {{"names", {"lambert"}}});
  EXPECT_EQ(bobAgain.status, 202) << "a cancelled queued job still counts: " << bobAgain;
  if (bobAgain.status == 202) jobs.emplace_back(b, jv(bobAgain.j(), "id", ""));
  // ... and within a pass for a running one (the comparison stops at its next pass).
  Reply cancelled = s.call(a, "DELETE", "/api/jobs/" + jobs[0].second);
  EXPECT_EQ(jv(cancelled.j(), "state", ""), "cancelled") << cancelled;
  Reply again;
  for (auto deadline = Clock::now() + std::chrono::seconds(10); Clock::now() < deadline;) {
    again = s.post(a, "/api/jobs/validate", {{"names", {"lambert"}}});
    if (again.status != 429) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(again.status, 202) << again;
  if (again.status == 202) jobs.emplace_back(a, jv(again.j(), "id", ""));
  for (const auto& [token, id] : jobs) s.call(token, "DELETE", "/api/jobs/" + id);
}

TEST_F(AuthQuotas, OneShotRendersAndAnalyses) {
  TestServer& s = *srv_;
  const std::string a = s.newStudent("qr-alice"), b = s.newStudent("qr-bob");
  // A render that takes minutes, kept in flight on a connection of its own.
  const json slow = {{"scene", furnaceScene("lambert", json::object(), 256, 65536, 1)}, {"spp", 65536}};
  const std::string body = slow.dump();
  auto openSlow = [&] {
    return openRaw(s.port(), "POST", "/api/render",
                   {{"Authorization", "Bearer " + a}, {"Content-Type", "application/json"}}, body);
  };
  int fd = openSlow();
  ASSERT_GE(fd, 0);
  // Once the server holds it, alice's next render is over her quota.
  Reply over;
  for (auto deadline = Clock::now() + std::chrono::seconds(20); Clock::now() < deadline;) {
    pollfd answered{fd, POLLIN, 0};
    if (::poll(&answered, 1, 0) > 0) {
      // The probe below got in first (the server read it before the slow one): start again.
      Reply early = readRaw(fd);
      ASSERT_EQ(early.status, 429) << "the slow render was answered: " << early;
      fd = openSlow();
      ASSERT_GE(fd, 0);
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      continue;
    }
    over = s.post(a, "/api/render", renderBody(tinyScene()));
    if (over.status == 429) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  expectQuota(over, "renders", 1, "alice's second render while one is in flight");
  expectQuota(s.post(a, "/api/analysis/polar", json::parse(R"({"series": [{"brdf": "lambert"}], "resolution": 3})")),
              "renders", 1, "alice's analysis while a render is in flight");
  Reply bobs = s.post(b, "/api/render", renderBody(tinyScene()));
  EXPECT_EQ(bobs.status, 200) << "bob is not affected: " << bobs;
  pollfd p{fd, POLLIN, 0};
  EXPECT_EQ(::poll(&p, 1, 0), 0) << "the slow render answered already";
  ::close(fd);  // the server stops the render before its next pass
  Reply freed;
  for (auto deadline = Clock::now() + std::chrono::seconds(20); Clock::now() < deadline;) {
    freed = s.post(a, "/api/render", renderBody(tinyScene()));
    if (freed.status == 200) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(freed.status, 200) << "alice's room came back when her render stopped: " << freed;
}

// A dozen requests of one student in flight together race for the last slots of each quota: exactly the
// quota's worth succeed, the rest are 429, and a classmate racing beside them is not affected.
TEST_F(AuthQuotas, RacingRequestsNeverPassAQuota) {
  TestServer& s = *srv_;
  const std::string a = s.newStudent("qx-alice"), b = s.newStudent("qx-bob");
  constexpr int kRacers = 12;
  // Runs attempt(i) for alice's kRacers and bob's one, released together once every thread is
  // ready; alice's statuses and bob's.
  auto race = [&](std::function<Reply(const std::string&, int)> attempt) {
    std::vector<int> statuses(kRacers + 1, 0);
    std::vector<std::thread> threads;
    std::atomic<int> ready{0};
    for (int i = 0; i <= kRacers; ++i)
      threads.emplace_back([&, i] {
        ready.fetch_add(1);
        while (ready.load() <= kRacers) std::this_thread::yield();
        statuses[i] = attempt(i < kRacers ? a : b, i).status;
      });
    for (std::thread& t : threads) t.join();
    const int bob = statuses.back();
    statuses.pop_back();
    return std::make_pair(statuses, bob);
  };
  auto count = [](const std::vector<int>& v, int status) { return int(std::count(v.begin(), v.end(), status)); };

  auto [sessions, bobSession] =
      race([&](const std::string& who, int) { return s.post(who, "/api/sessions", tinyScene()); });
  EXPECT_EQ(count(sessions, 201), 2) << "sessions made at once past --quota-sessions 2";
  EXPECT_EQ(count(sessions, 429), kRacers - 2);
  EXPECT_EQ(bobSession, 201);
  EXPECT_EQ(s.sessionIds(a).size() - s.sessionIds(a).count("default"), 2u);

  auto [brdfs, bobBrdf] = race([&](const std::string& who, int i) {
    const std::string name = (who == a ? "qx-alice/m" : "qx-bob/m") + std::to_string(i);
    return s.call(who, "PUT", "/api/brdfs/" + name, kLambertWhite, "text/plain");
  });
  EXPECT_EQ(count(brdfs, 201), 3) << "BRDFs saved at once past --quota-brdfs 3";
  EXPECT_EQ(count(brdfs, 429), kRacers - 3);
  EXPECT_EQ(bobBrdf, 201);
  int saved = 0;
  for (const json& e : s.get(a, "/api/brdfs").j()) saved += jv(e, "owner", "") == "qx-alice";
  EXPECT_EQ(saved, 3) << "alice's library holds more than her quota";

  auto [uploads, bobUpload] =
      race([&](const std::string& who, int i) { return s.upload(who, smallPng(), std::to_string(i) + ".png"); });
  EXPECT_EQ(count(uploads, 201), 2) << "uploads at once past --quota-uploads 2";
  // On a slow machine (a sanitizer build, a loaded CPU) the decode queue can fill before a racer
  // reaches the quota, and it is told 503 busy instead: refused either way.
  EXPECT_EQ(count(uploads, 429) + count(uploads, 503), kRacers - 2);
  EXPECT_EQ(bobUpload, 201);
  int kept = 0;
  for (const json& asset : s.get(a, "/api/assets").j()) kept += jv(asset, "owner", "") == "qx-alice";
  EXPECT_EQ(kept, 2) << "alice keeps more uploads than her quota";
}

// ---- Modes -----------------------------------------------------------------------------------

TEST(AuthModes, NoneOnAPublicAddressNeedsAllowUnauthenticated) {
  {
    Spawned refused;
    ASSERT_TRUE(refused.start({"--host", "0.0.0.0", "--auth", "none"}));
    EXPECT_EQ(refused.waitExit(std::chrono::seconds(30)), 2) << refused.log();
    // The reason comes first, before the usage (which lists every flag).
    const std::string reason = refused.log().substr(0, refused.log().find('\n'));
    EXPECT_NE(reason.find("--allow-unauthenticated"), std::string::npos) << refused.log();
  }
  {
    Spawned allowed;
    ASSERT_TRUE(allowed.start({"--host", "0.0.0.0", "--auth", "none", "--allow-unauthenticated"}));
    const int port = allowed.listeningPort(std::chrono::seconds(60));
    ASSERT_GT(port, 0) << allowed.log();
    const std::string log = lower(allowed.log());
    EXPECT_TRUE(log.find("warn") != std::string::npos || log.find("anyone") != std::string::npos)
        << "no warning at start-up:\n"
        << allowed.log();
    httplib::Client cli("127.0.0.1", port);
    auto me = cli.Get("/api/auth/me");
    ASSERT_TRUE(me);
    EXPECT_EQ(me->status, 200) << me->body;
    EXPECT_EQ(jv(bodyJson(me), "role", ""), "teacher");
    ::kill(allowed.pid, SIGTERM);
    EXPECT_EQ(allowed.waitExit(std::chrono::seconds(30)), 0);
  }
  {
    Spawned proxyWithoutFront;
    ASSERT_TRUE(proxyWithoutFront.start({"--auth", "proxy"}));
    EXPECT_EQ(proxyWithoutFront.waitExit(std::chrono::seconds(30)), 2) << proxyWithoutFront.log();
  }
}

// Any other --host defaults to tokens mode, with an admin token made on the first start.
TEST(AuthModes, PublicAddressDefaultsToTokensWithAGeneratedAdminToken) {
  Spawned server;
  ASSERT_TRUE(server.start({"--host", "0.0.0.0"}));
  const int port = server.listeningPort(std::chrono::seconds(60));
  ASSERT_GT(port, 0) << server.log();
  const std::string tokenFile = server.dir + "/data/auth/admin-token";
  struct stat st {};
  ASSERT_EQ(::stat(tokenFile.c_str(), &st), 0) << "no " << tokenFile << "\n" << server.log();
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  std::ifstream in(tokenFile);
  std::string token;
  std::getline(in, token);
  EXPECT_GE(token.size(), 16u);
  httplib::Client cli("127.0.0.1", port);
  auto anon = cli.Get("/api/auth/me");
  ASSERT_TRUE(anon);
  EXPECT_EQ(anon->status, 401) << "not tokens mode: " << anon->body;
  auto me = cli.Get("/api/auth/me", {{"Authorization", "Bearer " + token}});
  ASSERT_TRUE(me);
  EXPECT_EQ(me->status, 200) << me->body;
  EXPECT_EQ(jv(bodyJson(me), "role", ""), "teacher");
  EXPECT_EQ(jv(bodyJson(me), "mode", ""), "tokens");
  EXPECT_NE(server.log().find("admin-token"), std::string::npos) << "the log names the file:\n" << server.log();
  EXPECT_EQ(server.log().find(token), std::string::npos) << "the log holds the admin token";
  ::kill(server.pid, SIGTERM);
  EXPECT_EQ(server.waitExit(std::chrono::seconds(30)), 0);
}

TEST(AuthModes, ProxyTrustsTheUserHeaderFromItsFrontOnly) {
  TestServer s;
  ASSERT_EQ(s.startWith({"--auth", "proxy", "--proxy-from", "127.0.0.1/32", "--proxy-admin", "prof"}), "");
  auto as = [](const std::string& user, bool client = true) {
    httplib::Headers h = {{"X-Forwarded-User", user}};
    if (client) h.emplace("X-Brdfa-Client", "1");
    return h;
  };
  const std::string scene = tinyScene().dump();
  Reply me = s.call("", "GET", "/api/auth/me", "", "", as("Alice"));
  ASSERT_EQ(me.status, 200) << me;
  EXPECT_EQ(jv(me.j(), "mode", ""), "proxy");
  EXPECT_EQ(jv(me.j(), "user", ""), "alice") << "the header's value is lower-cased";
  EXPECT_EQ(jv(me.j(), "role", ""), "student");
  EXPECT_EQ(jv(me.j(), "namespace", ""), "alice/");
  EXPECT_EQ(jv(s.call("", "GET", "/api/auth/me", "", "", as("prof")).j(), "role", ""), "teacher");
  EXPECT_EQ(s.call("", "GET", "/api/auth/me", "", "", as("not a name!")).status, 401);
  EXPECT_EQ(s.get("", "/api/auth/me").status, 401);

  Reply a = s.call("", "POST", "/api/sessions", scene, "application/json", as("alice"));
  Reply b = s.call("", "POST", "/api/sessions", scene, "application/json", as("bob"));
  ASSERT_EQ(a.status, 201) << a;
  ASSERT_EQ(b.status, 201) << b;
  const std::string aid = jv(a.j(), "id", ""), bid = jv(b.j(), "id", "");
  auto listed = [&](const std::string& user) {
    std::set<std::string> ids;
    for (const json& e : s.call("", "GET", "/api/sessions", "", "", as(user)).j()) ids.insert(jv(e, "id", ""));
    return ids;
  };
  EXPECT_TRUE(listed("alice").count(aid));
  EXPECT_FALSE(listed("alice").count(bid)) << "alice sees bob's session";
  EXPECT_TRUE(listed("bob").count(bid));
  EXPECT_FALSE(listed("bob").count(aid)) << "bob sees alice's session";
  EXPECT_TRUE(listed("prof").count(aid) && listed("prof").count(bid));
  EXPECT_EQ(s.call("", "GET", "/api/sessions/" + aid, "", "", as("bob")).status, 404);

  // A state-changing request without X-Brdfa-Client (a cross-site form riding the SSO cookie).
  const size_t before = listed("prof").size();
  Reply noClient = s.call("", "POST", "/api/sessions", scene, "application/json", as("alice", false));
  EXPECT_EQ(noClient.status, 403) << noClient;
  Reply noClientDelete = s.call("", "DELETE", "/api/sessions/" + aid, "", "", as("alice", false));
  EXPECT_EQ(noClientDelete.status, 403) << noClientDelete;
  EXPECT_EQ(listed("prof").size(), before) << "a request without X-Brdfa-Client changed something";
  EXPECT_EQ(s.call("", "GET", "/api/sessions/" + aid, "", "", as("alice", false)).status, 200)
      << "reads need no X-Brdfa-Client";
  Reply evil = s.call("", "POST", "/api/sessions", scene, "application/json",
                      {{"X-Forwarded-User", "alice"}, {"X-Brdfa-Client", "1"}, {"Origin", "http://evil.example"}});
  EXPECT_EQ(evil.status, 403) << evil;
  EXPECT_EQ(evil.error(), "cross_site") << evil;

  // From an address that is not the front, the header is ignored.
  Reply elsewhere = rawRequest(s.port(), "GET", "/api/auth/me", as("alice"), "", "127.0.0.2");
  EXPECT_EQ(elsewhere.status, 401) << elsewhere;
  Reply elsewhereWrite =
      rawRequest(s.port(), "POST", "/api/sessions",
                 {{"X-Forwarded-User", "prof"}, {"X-Brdfa-Client", "1"}, {"Content-Type", "application/json"}}, scene,
                 "127.0.0.2");
  EXPECT_EQ(elsewhereWrite.status, 401) << elsewhereWrite;
  EXPECT_EQ(listed("prof").size(), before);

  // The token routes belong to tokens mode.
  for (const auto& [method, path] : std::vector<std::pair<std::string, std::string>>{{"POST", "/api/auth/users"},
                                                                                     {"GET", "/api/auth/users"},
                                                                                     {"POST", "/api/auth/join-codes"},
                                                                                     {"GET", "/api/auth/join-codes"},
                                                                                     {"POST", "/api/auth/logout"}}) {
    Reply r = s.call("", method, path, method == "POST" ? R"({"user": "x"})" : "", "application/json", as("prof"));
    EXPECT_EQ(r.status, 400) << method << " " << path << ": " << r;
    EXPECT_EQ(r.error(), "unsupported") << method << " " << path << ": " << r;
  }
  EXPECT_EQ(s.proc.terminate(), 0);
}

TEST(AuthModes, NoneOnLoopbackIsTheTeacher) {
  TestServer s;
  ASSERT_EQ(s.startWith({}), "");
  Reply me = s.get("", "/api/auth/me");
  ASSERT_EQ(me.status, 200) << me;
  EXPECT_EQ(jv(me.j(), "mode", ""), "none");
  EXPECT_EQ(jv(me.j(), "role", ""), "teacher");
  EXPECT_TRUE(me.j().contains("user") && me.j()["user"].is_null()) << me;
  Reply created = s.post("", "/api/sessions", tinyScene());
  EXPECT_EQ(created.status, 201) << created;
  EXPECT_EQ(s.call("", "PUT", "/api/brdfs/plain_name", kLambertWhite, "text/plain").status, 201)
      << "none mode saves bare names as before";
  EXPECT_EQ(s.post("", "/api/auth/users", {{"user", "x"}}).status, 400);
  EXPECT_EQ(jv(s.post("", "/api/auth/users", {{"user", "x"}}).j(), "error", ""), "unsupported");
  // Cross-site refusals hold in every mode.
  Reply evil =
      s.call("", "POST", "/api/sessions", tinyScene().dump(), "application/json", {{"Origin", "http://evil.example"}});
  EXPECT_EQ(evil.status, 403) << evil;
  EXPECT_EQ(evil.error(), "cross_site") << evil;
  EXPECT_EQ(corsHeaders(evil), "");
  EXPECT_EQ(s.proc.terminate(), 0);
}

}  // namespace
}  // namespace brdfa::itest
