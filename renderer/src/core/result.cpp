#include "brdfa/result.h"

namespace brdfa {

// Stable snake_case names: they appear in JSON error bodies and logs.
const char* errorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidArgument: return "invalid_argument";
    case ErrorCode::NotFound: return "not_found";
    case ErrorCode::CompileError: return "compile_error";
    case ErrorCode::Unsupported: return "unsupported";
    case ErrorCode::DeviceError: return "device_error";
    case ErrorCode::OverBudget: return "over_budget";
    case ErrorCode::RenderBudget: return "render_budget";
    case ErrorCode::Internal: return "internal";
  }
  return "internal";
}

}  // namespace brdfa
