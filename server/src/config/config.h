// Start-up settings of the HTTP service and their command-line parser (cpp-httplib's docker
// example style: one plain struct, one parse function, no globals).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace brdfa::server {

// The --auth modes.
enum class AuthMode { None, Tokens, Proxy };
const char* authModeName(AuthMode mode);  // "none", "tokens", "proxy"

// How requests say who asks (docs/api.md, Identities and ownership).
struct AuthSettings {
  AuthMode mode = AuthMode::None;                    // --auth; unset on the command line: none on loopback, else tokens
  bool allowUnauthenticated = false;                 // --allow-unauthenticated: none on a non-loopback address
  std::string adminTokenFile;                        // --admin-token-file (tokens mode)
  std::string proxyUserHeader = "X-Forwarded-User";  // --proxy-user-header (proxy mode)
  std::vector<std::string> proxyFrom;                // --proxy-from ADDR[/BITS], repeatable (proxy mode)
  std::vector<std::string> proxyAdmins;              // --proxy-admin NAME, repeatable (proxy mode)
};

// What one student may hold at once; the teacher has no quota. Each has a flag of its name.
struct Quotas {
  int sessions = 3;                     // --quota-sessions
  int brdfs = 100;                      // --quota-brdfs: saved BRDFs, the editor's scratch ones too
  int uploads = 20;                     // --quota-uploads
  uint64_t uploadBytes = 256ull << 20;  // --quota-upload-bytes
  int jobs = 2;                         // --quota-jobs: queued or running
  int renders = 1;                      // --quota-renders: one-shot renders and analyses in flight
};

struct ServerConfig {
  std::string host = "127.0.0.1";  // docs/design.md section 8: loopback unless told otherwise
  int port = 8080;                 // 0 = let the kernel pick a free port
  std::string root;                // holds shaders/ and web/
  std::string dataDir = "./data";  // brdfs/ (saved user BRDFs), presets/, uploads
  std::string deviceName;          // substring of the Vulkan device name; empty = best device
  int threads = 64;                // HTTP workers; every stream client holds one
  bool loadCache = true;           // --no-cache-load: compile afresh, then refresh the cache
  bool hotLoad = false;            // --hot-load: build cached BRDFs' pipelines after start-up
  int idleTimeoutSec = 30;         // a session with no watcher for this long stops rendering
  int sessionReclaimSec = 600;     // at the session cap, one unused this long makes room
  // Uploads (POST /api/assets), stored in <dataDir>/assets. Each limit has a flag of its name.
  uint64_t maxUploadBytes = 64ull << 20;    // --max-upload-bytes: one file's size
  uint64_t maxUploadTriangles = 2'000'000;  // --max-upload-triangles: of one mesh
  uint64_t maxUploadPixels = 16'777'216;    // --max-upload-pixels: width * height of one image
  int maxAssets = 1000;                     // --max-assets: stored uploads (0 disables uploads)
  uint64_t maxAssetsBytes = 4ull << 30;     // --max-assets-bytes: all stored upload files together
  int compileTimeoutSec = 5;                // --compile-timeout: one GLSL compile's wall clock
  int compileMemoryMiB = 0;  // --compile-memory: one GLSL compile's memory; 0: --max-memory / 16, in 64..1024
  // The render worker's watchdog (remote_renderer.h); --in-process turns it off.
  double buildBudgetSec = 10;   // --build-budget: one pipeline build
  double passBudgetSec = 1.5;   // --pass-budget: one queue submission of a pass
  double checkBudgetSec = 120;  // --check-budget: one submission of a BRDF check
  bool inProcess = false;       // --in-process: no render worker
  uint64_t maxMemoryMiB = 0;    // --max-memory: all sessions' render targets; 0: half the RAM
  // Slow or greedy clients: see ConnectionLimits in connection_guard.h.
  int maxConnectionsPerAddress = 32;  // --max-connections-per-address: open at once
  int requestReadTimeoutSec = 10;     // --request-read-timeout: to receive one request
  // --environment-dir (repeatable): folders whose *.exr become read-only environments
  // `blender_<stem>`. Unset: Debian blender-data's studio-light worlds, when installed.
  std::optional<std::vector<std::string>> environmentDirs;
  // Several replicas behind one balancer (docs/deploy.md). --replica (else
  // $BRDFA_REPLICA): this server's tag, [a-z0-9-] as a Kubernetes pod name; session and job ids
  // become <tag>.<id> so the balancer can route by path, and every response says X-Brdfa-Replica.
  std::string replica;
  // --drain-seconds: on SIGTERM, how long open streams and requests may go on (new sessions and
  // jobs are refused with 503 `draining`, /api/ready answers 503) before the server stops.
  double drainSeconds = 0;
  AuthSettings auth;
  Quotas quotas;
  int maxSessions = 32;  // --max-sessions: on this server, `default` included
};

// Whether `host` is a loopback address (127.0.0.0/8, ::1, localhost).
bool isLoopbackHost(std::string_view host);

// Whether `tag` may be a replica tag: 1-63 of [a-z0-9-], starting and ending alphanumeric.
bool isValidReplicaTag(std::string_view tag);

// What parse_command_line decided: run with `config`, or exit with `exitCode` after printing
// `message` (usage on --help goes to stdout with code 0; errors to stderr with code 2).
struct ParseOutcome {
  std::optional<ServerConfig> config;
  int exitCode = 0;
  std::string message;
};

// The root defaults to $BRDFA_ROOT when set, else the compiled-in source tree
// (BRDFA_DEFAULT_ROOT); `--root` overrides both.
ParseOutcome parse_command_line(int argc, const char* const* argv);

std::string usageText(const char* program);

}  // namespace brdfa::server
