// In-process GLSL -> SPIR-V with glslang.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "brdfa/result.h"

namespace brdfa {

enum class ShaderStage { Compute, Vertex, Fragment };

struct SpirvBinary {
  std::vector<uint32_t> words;
  std::vector<Diagnostic> warnings;
  double compileMs = 0;
};

// Compiles GLSL 450 for Vulkan 1.1 / SPIR-V 1.3 (subgroup operations; below SPIR-V 1.6 so the
// subgroup size is fixed). Thread-safe.
//
// Line mapping: the source uses `#line <n> 1` before submitted (user) text and `#line <n> 0`
// before generated text. Messages whose source-string number is 1 keep their line (the line in
// the submitted file); all others get line 0 and the prefix "in generated code: ".
// On failure returns ErrorCode::CompileError with one Diagnostic per compiler message, user
// lines first in line order.
Result<SpirvBinary> compileGlsl(ShaderStage stage, const std::string& source);

// Identifies the compiler, for cache keys (a new glslang must not reuse old SPIR-V).
std::string compilerVersion();

}  // namespace brdfa
