#include "config/config.h"

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <string_view>
#include <type_traits>

#include "util/address_range.h"
#include "util/user_name.h"

#ifndef BRDFA_DEFAULT_ROOT
#define BRDFA_DEFAULT_ROOT "."
#endif

namespace brdfa::server {

const char* authModeName(AuthMode mode) {
  switch (mode) {
    case AuthMode::None: return "none";
    case AuthMode::Tokens: return "tokens";
    case AuthMode::Proxy: return "proxy";
  }
  return "none";
}

namespace {

// Whole-string integer parse: "80x" or "" is an error, not 80 or 0.
std::optional<long long> parseInteger(std::string_view text) {
  long long value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || text.empty()) return std::nullopt;
  return value;
}

ParseOutcome fail(std::string message) {
  ParseOutcome out;
  out.exitCode = 2;
  out.message = std::move(message);
  return out;
}

// The auth mode from --auth (or its default for the host) and the flags it needs; the error
// message when they do not fit together.
std::optional<std::string> resolveAuth(ServerConfig& config, std::optional<AuthMode> chosen) {
  const bool loopback = isLoopbackHost(config.host);
  config.auth.mode = chosen ? *chosen : loopback ? AuthMode::None : AuthMode::Tokens;
  if (config.auth.mode == AuthMode::None && !loopback && !config.auth.allowUnauthenticated)
    return "--auth none on " + config.host +
           " would let anyone who reaches the port act as the teacher: add --allow-unauthenticated to mean it, "
           "or use --auth tokens";
  if (config.auth.mode == AuthMode::Proxy && config.auth.proxyFrom.empty())
    return "--auth proxy needs --proxy-from ADDR[/BITS]: the front whose user header is trusted";
  for (const std::string& range : config.auth.proxyFrom)
    if (!parseAddressRange(range))
      return "--proxy-from '" + range + "' is not an IPv4 or IPv6 address or ADDR/BITS range";
  for (const std::string& name : config.auth.proxyAdmins)
    if (!isValidUserName(name)) return "--proxy-admin '" + name + "' is not a valid user name ([a-z0-9._@-], 1-64)";
  return std::nullopt;
}

}  // namespace

bool isLoopbackHost(std::string_view host) {
  return host == "localhost" || host == "::1" || host == "[::1]" || host.starts_with("127.");
}

bool isValidReplicaTag(std::string_view tag) {
  if (tag.empty() || tag.size() > 63 || tag.front() == '-' || tag.back() == '-') return false;
  for (char c : tag)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-')) return false;
  return true;
}

std::string usageText(const char* program) {
  std::string p = program ? program : "brdfa-server";
  return "usage: " + p +
         " [options]\n"
         "  --port N          TCP port (default 8080; 0 picks a free port)\n"
         "  --host ADDR       address to bind (default 127.0.0.1)\n"
         "  --root DIR        directory holding shaders/ and web/ (default $BRDFA_ROOT or the\n"
         "                    source tree the server was built from)\n"
         "  --data-dir DIR    where user data lives (default ./data)\n"
         "  --device NAME     pick the Vulkan device whose name contains NAME\n"
         "  --threads N       HTTP worker threads (default 64; each stream client holds one)\n"
         "  --idle-timeout S  seconds a session keeps rendering without a watcher (default 30)\n"
         "  --session-reclaim S  at the session cap, a new session replaces the one unused for\n"
         "                    longest if unused for S seconds (default 600; `default` is kept)\n"
         "  --no-cache-load   ignore cached SPIR-V (<data-dir>/cache/spirv), compile afresh and\n"
         "                    refresh the cache\n"
         "  --max-upload-bytes N      largest uploaded asset file in bytes (default 67108864 = 64 MiB)\n"
         "  --max-upload-triangles N  most triangles in one uploaded mesh (default 2000000)\n"
         "  --max-upload-pixels N     most pixels (width * height) in one uploaded image\n"
         "                            (default 16777216 = 4096 x 4096)\n"
         "  --max-assets N            most uploads kept in <data-dir>/assets (default 1000; 0 refuses\n"
         "                            uploads)\n"
         "  --max-assets-bytes N      most bytes all kept uploads may take together (default\n"
         "                            4294967296 = 4 GiB)\n"
         "  --compile-timeout S       seconds one GLSL compile may take (default 5)\n"
         "  --compile-memory MIB      memory one GLSL compile may use, in MiB (default: a sixteenth\n"
         "                            of --max-memory, within 64..1024); a program past either\n"
         "                            budget is refused with 422\n"
         "  --build-budget S          seconds the driver may take to build one BRDF's pipeline\n"
         "                            (default 10)\n"
         "  --pass-budget S           seconds one queue submission of a pass may take (default 1.5;\n"
         "                            passes are split into submissions of about 50 ms, and every\n"
         "                            other session waits while one runs)\n"
         "  --check-budget S          seconds one submission of a BRDF's checks may take (default 120).\n"
         "                            Past any budget the render worker is restarted, the BRDF is\n"
         "                            quarantined (422 render_budget) and other sessions go on\n"
         "  --in-process              open the device in the server's own process, without the\n"
         "                            supervised render worker (debugging; no watchdog)\n"
         "  --max-memory MIB          memory all the server's processes may hold, in MiB (default:\n"
         "                            half the machine's RAM): render targets, assets, programs,\n"
         "                            compiles and uploads in flight. Unused cached programs and\n"
         "                            assets are dropped to make room; then a scene or upload\n"
         "                            that would pass it is refused with 507\n"
         "  --max-connections-per-address N\n"
         "                            connections one client address may hold open at once\n"
         "                            (default 32); past it a connection gets 503 at once. Keep it\n"
         "                            below --threads, or one address can take every worker\n"
         "  --request-read-timeout S  seconds a client has to send a request's line and headers,\n"
         "                            counted from the connection's accept or the previous response\n"
         "                            (default 10); the body gets S more, plus 1 s per 16 KiB\n"
         "                            received. A client too slow is disconnected\n"
         "  --environment-dir DIR     register every *.exr in DIR that the renderer can read as the\n"
         "                            read-only environment blender_<name>; repeatable (default:\n"
         "                            Debian blender-data's\n"
         "                            /usr/share/blender/datafiles/studiolights/world and\n"
         "                            /usr/share/blender/*/datafiles/studiolights/world, if present)\n"
         "  --hot-load        after start-up, build in the background the pipelines of every\n"
         "                    BRDF whose SPIR-V is cached (never compiling GLSL), so BRDFs used\n"
         "                    before are instant on first use; without it BRDFs compile on\n"
         "                    first use and start-up prepares nothing\n"
         "  --replica NAME    this replica's tag behind a balancer (default $BRDFA_REPLICA, else\n"
         "                    none): 1-63 of [a-z0-9-]; session and job ids become NAME.<id>\n"
         "                    (docs/deploy.md)\n"
         "  --drain-seconds S on SIGTERM, refuse new sessions and jobs (503 draining) and let open\n"
         "                    streams and requests go on for up to S seconds, then stop (default\n"
         "                    0: stop at once). A second SIGTERM, or SIGINT, stops at once\n"
         "  --auth MODE       who asks: none (no identities; the default on a loopback --host),\n"
         "                    tokens (personal bearer tokens; the default elsewhere) or proxy\n"
         "                    (a user header from a trusted front); docs/api.md, Identities\n"
         "  --allow-unauthenticated  permit --auth none on a non-loopback --host (warns)\n"
         "  --admin-token-file PATH  the teacher's token, its first line (default\n"
         "                    $BRDFA_ADMIN_TOKEN, else <data-dir>/auth/admin-token, made on first start)\n"
         "  --proxy-user-header NAME  proxy mode: the header naming the user (default X-Forwarded-User)\n"
         "  --proxy-from ADDR[/BITS]  proxy mode: an address the header is trusted from; repeatable\n"
         "  --proxy-admin NAME        proxy mode: a user who is a teacher; repeatable\n"
         "  --max-sessions N  sessions on this server, `default` included (default 32)\n"
         "  --quota-sessions N, --quota-brdfs N, --quota-uploads N, --quota-upload-bytes N,\n"
         "  --quota-jobs N, --quota-renders N\n"
         "                    what one student may hold (defaults 3, 100, 20, 268435456, 2, 1);\n"
         "                    past one the answer is 429 quota_exceeded\n"
         "  --help            show this text\n"
         "On start prints one line `listening on http://HOST:PORT` to stdout.\n";
}

namespace {

// What the flags set: the config, and --auth until its default for the host is known.
struct ParseState {
  ServerConfig config;
  std::optional<AuthMode> authMode;
};

// The value of the flag at argv[i] (`--flag value` or `--flag=value`), read as each flag needs.
// Every reader returns the error message, or nullopt when it stored the value.
struct FlagReader {
  int argc;
  const char* const* argv;
  int& i;
  std::string_view name;
  std::optional<std::string> inlineValue;

  std::optional<std::string> takeValue() {
    if (inlineValue) return inlineValue;
    if (i + 1 >= argc) return std::nullopt;
    return std::string(argv[++i]);
  }
  // An integer in lo..hi into `dst` (int or uint64_t).
  template <class T>
  std::optional<std::string> takeInt(long long lo, long long hi, T& dst) {
    auto v = takeValue();
    if (!v) return std::string(name) + " needs a value";
    auto n = parseInteger(*v);
    if (!n || *n < lo || *n > hi)
      return std::string(name) + " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
             ", got '" + *v + "'";
    dst = static_cast<T>(*n);
    return std::nullopt;
  }
  // A number of seconds in lo..hi, fractions allowed.
  std::optional<std::string> takeSeconds(double lo, double hi, double& dst) {
    auto v = takeValue();
    if (!v) return std::string(name) + " needs a value";
    char* end = nullptr;
    const double s = std::strtod(v->c_str(), &end);
    if (v->empty() || end != v->c_str() + v->size() || !(s >= lo && s <= hi)) {
      char range[64];
      std::snprintf(range, sizeof range, "%g..%g", lo, hi);
      return std::string(name) + " must be a number of seconds in " + range + ", got '" + *v + "'";
    }
    dst = s;
    return std::nullopt;
  }
  std::optional<std::string> takeString(std::string& dst) {
    auto v = takeValue();
    if (!v || v->empty()) return std::string(name) + " needs a non-empty value";
    dst = *v;
    return std::nullopt;
  }
};

std::optional<std::string> takeAuthMode(FlagReader& r, ParseState& st) {
  std::string mode;
  if (auto err = r.takeString(mode)) return err;
  if (mode == "none")
    st.authMode = AuthMode::None;
  else if (mode == "tokens")
    st.authMode = AuthMode::Tokens;
  else if (mode == "proxy")
    st.authMode = AuthMode::Proxy;
  else
    return "--auth must be none, tokens or proxy, got '" + mode + "'";
  return std::nullopt;
}

std::optional<std::string> takeRepeated(FlagReader& r, std::vector<std::string>& list) {
  std::string value;
  if (auto err = r.takeString(value)) return err;
  list.push_back(value);
  return std::nullopt;
}

// The flags that take a value, each with its reader (usageText documents them).
using FlagParser = std::optional<std::string> (*)(FlagReader&, ParseState&);
struct ValueFlag {
  std::string_view name;
  FlagParser parse;
};
using R = FlagReader;
using S = ParseState;
const ValueFlag kValueFlags[] = {
    {"--port", [](R& r, S& s) { return r.takeInt(0, 65535, s.config.port); }},
    {"--host", [](R& r, S& s) { return r.takeString(s.config.host); }},
    {"--root", [](R& r, S& s) { return r.takeString(s.config.root); }},
    {"--data-dir", [](R& r, S& s) { return r.takeString(s.config.dataDir); }},
    {"--device", [](R& r, S& s) { return r.takeString(s.config.deviceName); }},
    {"--threads", [](R& r, S& s) { return r.takeInt(2, 1024, s.config.threads); }},
    {"--idle-timeout", [](R& r, S& s) { return r.takeInt(1, 24 * 3600, s.config.idleTimeoutSec); }},
    {"--session-reclaim", [](R& r, S& s) { return r.takeInt(1, 7 * 24 * 3600, s.config.sessionReclaimSec); }},
    {"--max-upload-bytes", [](R& r, S& s) { return r.takeInt(1, 1ll << 30, s.config.maxUploadBytes); }},
    {"--max-upload-triangles", [](R& r, S& s) { return r.takeInt(1, 100'000'000, s.config.maxUploadTriangles); }},
    {"--max-upload-pixels", [](R& r, S& s) { return r.takeInt(1, 1ll << 28, s.config.maxUploadPixels); }},
    {"--max-assets", [](R& r, S& s) { return r.takeInt(0, 1'000'000, s.config.maxAssets); }},
    {"--max-assets-bytes", [](R& r, S& s) { return r.takeInt(0, 1ll << 50, s.config.maxAssetsBytes); }},
    {"--compile-timeout", [](R& r, S& s) { return r.takeInt(1, 600, s.config.compileTimeoutSec); }},
    {"--compile-memory", [](R& r, S& s) { return r.takeInt(64, 1 << 20, s.config.compileMemoryMiB); }},
    {"--build-budget", [](R& r, S& s) { return r.takeSeconds(0.1, 3600, s.config.buildBudgetSec); }},
    {"--pass-budget", [](R& r, S& s) { return r.takeSeconds(0.1, 3600, s.config.passBudgetSec); }},
    {"--check-budget", [](R& r, S& s) { return r.takeSeconds(0.1, 3600, s.config.checkBudgetSec); }},
    {"--max-memory", [](R& r, S& s) { return r.takeInt(16, 1ll << 30, s.config.maxMemoryMiB); }},
    {"--max-connections-per-address",
     [](R& r, S& s) { return r.takeInt(1, 1'000'000, s.config.maxConnectionsPerAddress); }},
    {"--request-read-timeout", [](R& r, S& s) { return r.takeInt(1, 3600, s.config.requestReadTimeoutSec); }},
    {"--replica", [](R& r, S& s) { return r.takeString(s.config.replica); }},
    {"--drain-seconds", [](R& r, S& s) { return r.takeSeconds(0, 3600, s.config.drainSeconds); }},
    {"--auth", takeAuthMode},
    {"--admin-token-file", [](R& r, S& s) { return r.takeString(s.config.auth.adminTokenFile); }},
    {"--proxy-user-header", [](R& r, S& s) { return r.takeString(s.config.auth.proxyUserHeader); }},
    {"--proxy-from", [](R& r, S& s) { return takeRepeated(r, s.config.auth.proxyFrom); }},
    {"--proxy-admin", [](R& r, S& s) { return takeRepeated(r, s.config.auth.proxyAdmins); }},
    {"--max-sessions", [](R& r, S& s) { return r.takeInt(2, 100000, s.config.maxSessions); }},
    {"--quota-sessions", [](R& r, S& s) { return r.takeInt(1, 100000, s.config.quotas.sessions); }},
    {"--quota-brdfs", [](R& r, S& s) { return r.takeInt(1, 1000000, s.config.quotas.brdfs); }},
    {"--quota-uploads", [](R& r, S& s) { return r.takeInt(0, 1000000, s.config.quotas.uploads); }},
    {"--quota-upload-bytes", [](R& r, S& s) { return r.takeInt(0, 1ll << 50, s.config.quotas.uploadBytes); }},
    {"--quota-jobs", [](R& r, S& s) { return r.takeInt(1, 1000, s.config.quotas.jobs); }},
    {"--quota-renders", [](R& r, S& s) { return r.takeInt(1, 1000, s.config.quotas.renders); }},
    {"--environment-dir",
     [](R& r, S& s) {
       if (!s.config.environmentDirs) s.config.environmentDirs.emplace();
       return takeRepeated(r, *s.config.environmentDirs);
     }},
};

// The flags without a value; false for any other argument.
bool takeSwitch(std::string_view arg, ServerConfig& config) {
  if (arg == "--no-cache-load")
    config.loadCache = false;
  else if (arg == "--in-process")
    config.inProcess = true;
  else if (arg == "--hot-load")
    config.hotLoad = true;
  else if (arg == "--allow-unauthenticated")
    config.auth.allowUnauthenticated = true;
  else
    return false;
  return true;
}

// Reads the value flag at argv[i] (advancing i past its value); the error message otherwise.
std::optional<std::string> takeValueFlag(int argc, const char* const* argv, int& i, ParseState& state) {
  const std::string_view arg = argv[i];
  FlagReader reader{argc, argv, i, arg, std::nullopt};
  if (size_t eq = arg.find('='); arg.starts_with("--") && eq != std::string_view::npos) {
    reader.name = arg.substr(0, eq);
    reader.inlineValue = std::string(arg.substr(eq + 1));
  }
  for (const ValueFlag& flag : kValueFlags)
    if (flag.name == reader.name) return flag.parse(reader, state);
  return "unknown option '" + std::string(arg) + "'";
}

}  // namespace

ParseOutcome parse_command_line(int argc, const char* const* argv) {
  ParseState state;
  ServerConfig& config = state.config;
  const char* envRoot = std::getenv("BRDFA_ROOT");
  config.root = (envRoot && *envRoot) ? envRoot : BRDFA_DEFAULT_ROOT;
  const char* envReplica = std::getenv("BRDFA_REPLICA");
  if (envReplica) config.replica = envReplica;

  for (int i = 1; i < argc; ++i) {
    std::string_view arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      ParseOutcome out;
      out.exitCode = 0;
      out.message = usageText(argv[0]);
      return out;
    }
    if (takeSwitch(arg, config)) continue;
    if (std::optional<std::string> err = takeValueFlag(argc, argv, i, state))
      return fail(*err + "\n" + usageText(argv[0]));
  }
  if (!config.replica.empty() && !isValidReplicaTag(config.replica))
    return fail(
        "--replica (or $BRDFA_REPLICA) must be 1-63 of [a-z0-9-], starting and ending with a letter or "
        "digit, got '" +
        config.replica + "'\n" + usageText(argv[0]));
  if (std::optional<std::string> err = resolveAuth(config, state.authMode))
    return fail(*err + "\n" + usageText(argv[0]));
  ParseOutcome out;
  out.config = config;
  return out;
}

}  // namespace brdfa::server
