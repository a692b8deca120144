// Errors as values (vk-bootstrap style): nothing in the renderer throws across its API or aborts.
#pragma once

#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace brdfa {

// What kind of failure. Each code has one wire name and one HTTP status (errorCodeName,
// errorHttpStatus: the table in result.cpp); the server answers every error through them.
// Codes are appended, never reordered: the render worker sends them as numbers.
enum class ErrorCode {
  InvalidArgument,  // the caller passed something malformed or out of range
  NotFound,         // a named thing (environment, mesh, parameter) does not exist
  CompileError,     // BRDF source failed to parse or compile; see diagnostics
  Unsupported,      // valid request the device or build cannot do
  DeviceError,      // Vulkan failed (out of memory, device lost, ...)
  OverBudget,       // the request needs more of a server-wide budget (memory) than is left
  RenderBudget,     // the program (or scene) took the render worker past its time or memory
                    // budget and is quarantined (RendererOptions::isolate)
  Internal,         // a bug: an invariant did not hold
  // Failures of an HTTP request itself, answered by the server (docs/api.md, Errors).
  BadJson,             // the body is not JSON
  Unauthorized,        // no valid credentials
  Forbidden,           // the requester may see the thing but not do this to it
  Conflict,            // the request clashes with the thing's current state
  NoScene,             // the session has no scene yet
  PayloadTooLarge,     // the body or an upload is over a limit
  TooManySessions,     // the server's session cap is reached
  TooManyJobs,         // the job queue is full
  QuotaExceeded,       // one person is past one of their quotas
  ClientClosed,        // the client went away before the answer
  StorageError,        // reading or writing the data directory failed
  StorageFull,         // the data directory (or the uploads' budget) is full
  Busy,                // a shared slot (render, frame wait) did not free up in time
  Unavailable,         // the thing stopped or the server is shutting down
  TooManyStreams,      // the cap on concurrent streams is reached
  TooManyConnections,  // one address holds too many connections
  Draining,            // the server takes no new sessions or jobs (SIGTERM)
  CrossSite,           // a state-changing request from a page of another site
};

// The snake_case name clients see as "error" in JSON bodies ("invalid_argument", ...).
const char* errorCodeName(ErrorCode code);
// The HTTP status the server answers the code with.
int errorHttpStatus(ErrorCode code);

// One compiler or parser message. `line` is 1-based in the submitted .brdf text;
// 0 means the message is not attributable to a line of the submitted text.
struct Diagnostic {
  int line = 0;
  int column = 0;                  // 0 when unknown
  std::string severity = "error";  // "error" | "warning"
  std::string message;
};

struct Error {
  ErrorCode code = ErrorCode::Internal;
  std::string message;
  std::string field;                    // offending input field, e.g. "objects[0].params.Kd"
  std::vector<Diagnostic> diagnostics;  // for CompileError
};

inline Error makeError(ErrorCode code, std::string message, std::string field = {}) {
  return Error{code, std::move(message), std::move(field), {}};
}

// Holds either a T or an Error.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}
  Result(Error error) : v_(std::move(error)) {}

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & { return std::get<0>(v_); }
  const T& value() const& { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() { return value(); }

  const Error& error() const { return std::get<1>(v_); }
  Error&& takeError() { return std::get<1>(std::move(v_)); }

 private:
  std::variant<T, Error> v_;
};

template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(Error error) : error_(std::move(error)), ok_(false) {}

  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const Error& error() const { return error_; }
  Error&& takeError() { return std::move(error_); }

 private:
  Error error_;
  bool ok_ = true;
};

}  // namespace brdfa

// Propagates an Error from a Result-returning expression: returns it from the enclosing function
// (whose return type is a Result or an Error) on failure.
#define BRDFA_TRY(expr)                                      \
  do {                                                       \
    auto brdfa_try_r_ = (expr);                              \
    if (!brdfa_try_r_.ok()) return brdfa_try_r_.takeError(); \
  } while (0)

#define BRDFA_CONCAT_INNER_(a, b) a##b
#define BRDFA_CONCAT_(a, b) BRDFA_CONCAT_INNER_(a, b)
// Declares `lhs` (e.g. `auto x` or `Scene scene`) from a Result<T>-returning expression's value,
// or returns its Error from the enclosing function.
#define BRDFA_TRY_ASSIGN(lhs, expr) BRDFA_TRY_ASSIGN_IMPL_(BRDFA_CONCAT_(brdfa_try_a_, __LINE__), lhs, expr)
#define BRDFA_TRY_ASSIGN_IMPL_(tmp, lhs, expr) \
  auto tmp = (expr);                           \
  if (!tmp.ok()) return tmp.takeError();       \
  lhs = std::move(tmp.value())
