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
    if (!parseAddressRange(range)) return "--proxy-from '" + range + "' is not an IPv4 or IPv6 address or ADDR/BITS range";
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

ParseOutcome parse_command_line(int argc, const char* const* argv) {
  ServerConfig config;
  const char* envRoot = std::getenv("BRDFA_ROOT");
  config.root = (envRoot && *envRoot) ? envRoot : BRDFA_DEFAULT_ROOT;
  const char* envReplica = std::getenv("BRDFA_REPLICA");
  if (envReplica) config.replica = envReplica;

  std::optional<AuthMode> authMode;
  for (int i = 1; i < argc; ++i) {
    std::string_view arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      ParseOutcome out;
      out.exitCode = 0;
      out.message = usageText(argv[0]);
      return out;
    }
    if (arg == "--no-cache-load") {
      config.loadCache = false;
      continue;
    }
    if (arg == "--in-process") {
      config.inProcess = true;
      continue;
    }
    if (arg == "--hot-load") {
      config.hotLoad = true;
      continue;
    }
    if (arg == "--allow-unauthenticated") {
      config.auth.allowUnauthenticated = true;
      continue;
    }
    // Accept both `--flag value` and `--flag=value`.
    std::string_view name = arg;
    std::optional<std::string> inlineValue;
    if (size_t eq = arg.find('='); arg.starts_with("--") && eq != std::string_view::npos) {
      name = arg.substr(0, eq);
      inlineValue = std::string(arg.substr(eq + 1));
    }
    auto takeValue = [&]() -> std::optional<std::string> {
      if (inlineValue) return inlineValue;
      if (i + 1 >= argc) return std::nullopt;
      return std::string(argv[++i]);
    };
    // An integer in lo..hi into `dst` (int or uint64_t); the error message otherwise.
    auto takeInt = [&](long long lo, long long hi, auto& dst) -> std::optional<std::string> {
      auto v = takeValue();
      if (!v) return std::string(name) + " needs a value";
      auto n = parseInteger(*v);
      if (!n || *n < lo || *n > hi)
        return std::string(name) + " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
               ", got '" + *v + "'";
      dst = static_cast<std::remove_reference_t<decltype(dst)>>(*n);
      return std::nullopt;
    };
    // A number of seconds in lo..hi, fractions allowed.
    auto takeSeconds = [&](double lo, double hi, double& dst) -> std::optional<std::string> {
      auto v = takeValue();
      if (!v) return std::string(name) + " needs a value";
      char* end = nullptr;
      const double s = std::strtod(v->c_str(), &end);
      if (v->empty() || end != v->c_str() + v->size() || !(s >= lo && s <= hi))
      {
        char range[64];
        std::snprintf(range, sizeof range, "%g..%g", lo, hi);
        return std::string(name) + " must be a number of seconds in " + range + ", got '" + *v + "'";
      }
      dst = s;
      return std::nullopt;
    };
    auto takeString = [&](std::string& dst) -> std::optional<std::string> {
      auto v = takeValue();
      if (!v || v->empty()) return std::string(name) + " needs a non-empty value";
      dst = *v;
      return std::nullopt;
    };

    std::optional<std::string> err;
    if (name == "--port")
      err = takeInt(0, 65535, config.port);
    else if (name == "--host")
      err = takeString(config.host);
    else if (name == "--root")
      err = takeString(config.root);
    else if (name == "--data-dir")
      err = takeString(config.dataDir);
    else if (name == "--device")
      err = takeString(config.deviceName);
    else if (name == "--threads")
      err = takeInt(2, 1024, config.threads);
    else if (name == "--idle-timeout")
      err = takeInt(1, 24 * 3600, config.idleTimeoutSec);
    else if (name == "--session-reclaim")
      err = takeInt(1, 7 * 24 * 3600, config.sessionReclaimSec);
    else if (name == "--max-upload-bytes")
      err = takeInt(1, 1ll << 30, config.maxUploadBytes);
    else if (name == "--max-upload-triangles")
      err = takeInt(1, 100'000'000, config.maxUploadTriangles);
    else if (name == "--max-upload-pixels")
      err = takeInt(1, 1ll << 28, config.maxUploadPixels);
    else if (name == "--max-assets")
      err = takeInt(0, 1'000'000, config.maxAssets);
    else if (name == "--max-assets-bytes")
      err = takeInt(0, 1ll << 50, config.maxAssetsBytes);
    else if (name == "--compile-timeout")
      err = takeInt(1, 600, config.compileTimeoutSec);
    else if (name == "--compile-memory")
      err = takeInt(64, 1 << 20, config.compileMemoryMiB);
    else if (name == "--build-budget")
      err = takeSeconds(0.1, 3600, config.buildBudgetSec);
    else if (name == "--pass-budget")
      err = takeSeconds(0.1, 3600, config.passBudgetSec);
    else if (name == "--check-budget")
      err = takeSeconds(0.1, 3600, config.checkBudgetSec);
    else if (name == "--max-memory")
      err = takeInt(16, 1ll << 30, config.maxMemoryMiB);
    else if (name == "--max-connections-per-address")
      err = takeInt(1, 1'000'000, config.maxConnectionsPerAddress);
    else if (name == "--request-read-timeout")
      err = takeInt(1, 3600, config.requestReadTimeoutSec);
    else if (name == "--replica")
      err = takeString(config.replica);
    else if (name == "--drain-seconds")
      err = takeSeconds(0, 3600, config.drainSeconds);
    else if (name == "--auth") {
      std::string mode;
      err = takeString(mode);
      if (!err) {
        if (mode == "none") authMode = AuthMode::None;
        else if (mode == "tokens") authMode = AuthMode::Tokens;
        else if (mode == "proxy") authMode = AuthMode::Proxy;
        else err = "--auth must be none, tokens or proxy, got '" + mode + "'";
      }
    } else if (name == "--admin-token-file")
      err = takeString(config.auth.adminTokenFile);
    else if (name == "--proxy-user-header")
      err = takeString(config.auth.proxyUserHeader);
    else if (name == "--proxy-from" || name == "--proxy-admin") {
      std::string value;
      err = takeString(value);
      if (!err) (name == "--proxy-from" ? config.auth.proxyFrom : config.auth.proxyAdmins).push_back(value);
    } else if (name == "--max-sessions")
      err = takeInt(2, 100000, config.maxSessions);
    else if (name == "--quota-sessions")
      err = takeInt(1, 100000, config.quotas.sessions);
    else if (name == "--quota-brdfs")
      err = takeInt(1, 1000000, config.quotas.brdfs);
    else if (name == "--quota-uploads")
      err = takeInt(0, 1000000, config.quotas.uploads);
    else if (name == "--quota-upload-bytes")
      err = takeInt(0, 1ll << 50, config.quotas.uploadBytes);
    else if (name == "--quota-jobs")
      err = takeInt(1, 1000, config.quotas.jobs);
    else if (name == "--quota-renders")
      err = takeInt(1, 1000, config.quotas.renders);
    else if (name == "--environment-dir") {
      std::string dir;
      err = takeString(dir);
      if (!err) {
        if (!config.environmentDirs) config.environmentDirs.emplace();
        config.environmentDirs->push_back(dir);
      }
    }
    else
      err = "unknown option '" + std::string(arg) + "'";
    if (err) return fail(*err + "\n" + usageText(argv[0]));
  }
  if (!config.replica.empty() && !isValidReplicaTag(config.replica))
    return fail("--replica (or $BRDFA_REPLICA) must be 1-63 of [a-z0-9-], starting and ending with a letter or "
                "digit, got '" + config.replica + "'\n" + usageText(argv[0]));
  if (std::optional<std::string> err = resolveAuth(config, authMode)) return fail(*err + "\n" + usageText(argv[0]));
  ParseOutcome out;
  out.config = config;
  return out;
}

}  // namespace brdfa::server
