// Errors as values (vk-bootstrap style): nothing in the renderer throws across its API or aborts.
#pragma once

#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace brdfa {

// What kind of failure; the server maps each code to one HTTP status in one place.
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
};

const char* errorCodeName(ErrorCode code);

// One compiler or parser message. `line` is 1-based in the submitted .brdf text;
// 0 means the message is not attributable to a line of the submitted text.
struct Diagnostic {
  int line = 0;
  int column = 0;  // 0 when unknown
  std::string severity = "error";  // "error" | "warning"
  std::string message;
};

struct Error {
  ErrorCode code = ErrorCode::Internal;
  std::string message;
  std::string field;                     // offending input field, e.g. "objects[0].params.Kd"
  std::vector<Diagnostic> diagnostics;   // for CompileError
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
