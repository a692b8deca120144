// Assembles a shading program in the fixed order of docs/design.md section 2:
//   prelude (#version, extensions, defines), generated uniforms (the BRDF's parameter block),
//   common code (shaders/lib), the BRDF (user text under `#line`), the integrator (with main).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "brdfa/brdf.h"

namespace brdfa {

// std140 layout of the BRDF's parameters, packed into one uniform block:
//   layout(std140, set = 1, binding = 0) uniform BrdfParams { float roughness; vec3 Kd; bool iso; };
// Members keep the parameter names, so user code reads them as plain globals.
struct ParamBlockLayout {
  struct Entry {
    std::string name;
    ParamType type;
    uint32_t offset;  // bytes
  };
  std::vector<Entry> entries;
  uint32_t size = 16;  // bytes, a multiple of 16, never 0 (an empty block gets a pad member)

  // The GLSL declaration of the block.
  std::string glsl() const;
  // Packs values (missing names take the BRDF's defaults; Bool writes uint 0/1) into `size` bytes.
  std::vector<uint8_t> pack(const BrdfDefinition& brdf, const std::map<std::string, Vec3>& values) const;
};

ParamBlockLayout layoutParams(const std::vector<BrdfParam>& params);

struct ProgramSpec {
  const BrdfDefinition* brdf = nullptr;
  std::vector<std::string> defines;       // "NAME" or "NAME VALUE", emitted as #define in the prelude
  // GLSL text of shaders/lib pieces, in order. userChunks come before the BRDF's text (what it
  // may read: its inputs); commonChunks after it, so the BRDF's text cannot name the
  // integrator's resources, and the macros it defines are #undef'd before them.
  std::vector<std::string> userChunks;
  std::vector<std::string> commonChunks;
  std::string integrator;                 // kernel text containing main()
};

struct AssembledProgram {
  std::string source;
  ParamBlockLayout params;
  uint64_t hash = 0;  // FNV-1a 64 of `source`
};

// Never fails: syntax problems surface when the result is compiled. Generated parts are emitted
// under `#line 1 0` so only the BRDF's own text is reported against file lines.
AssembledProgram assembleProgram(const ProgramSpec& spec);

// The default seed is the FNV-1a 64 offset basis (0xcbf29ce484222325).
uint64_t fnv1a64(const std::string& bytes, uint64_t seed = 14695981039346656037ull);

}  // namespace brdfa
