// Assembles a shading program in the fixed order of docs/design.md section 3.1:
//   prelude (#version, extensions, defines), generated uniforms (the BRDF's parameter block),
//   the BRDF's inputs, the shared terms its text includes (shaders/lib/terms), the BRDF (user
//   text under `#line`), common code (shaders/lib), the integrator (with main).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <string_view>
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

// GLSL text of the shared terms, shaders/lib/terms/<name>.glsl, keyed "terms/<name>.glsl".
using TermSources = std::map<std::string, std::string>;

// One line of BRDF text read as a term include, `#include "terms/<name>.glsl"` (<name> of
// a-z, 0-9 and '_'; a trailing `//` comment is allowed). `isInclude` is false for any other
// line; for an include, `path` is the term's key, or `error` says why the line is malformed
// (another folder, `..`, an absolute path, <...> quotes).
struct TermInclude {
  bool isInclude = false;
  std::string path;
  std::string error;
};
TermInclude parseTermInclude(std::string_view line);

// The terms a ProgramSpec without its own `terms` resolves against: those ShaderSources::load
// read last (empty before any load). Safe to call from any thread.
void setDefaultTermSources(TermSources terms);
std::shared_ptr<const TermSources> defaultTermSources();

struct ProgramSpec {
  const BrdfDefinition* brdf = nullptr;
  std::vector<std::string> defines;  // "NAME" or "NAME VALUE", emitted as #define in the prelude
  // GLSL text of shaders/lib pieces, in order. userChunks come before the BRDF's text (what it
  // may read: its inputs); commonChunks after it, so the BRDF's text cannot name the
  // integrator's resources, and the macros it defines are #undef'd before them.
  std::vector<std::string> userChunks;
  std::vector<std::string> commonChunks;
  std::string integrator;  // kernel text containing main()
  // Where the BRDF's `#include "terms/<name>.glsl"` lines resolve; null: defaultTermSources().
  const TermSources* terms = nullptr;
};

struct AssembledProgram {
  std::string source;
  ParamBlockLayout params;
  uint64_t hash = 0;  // FNV-1a 64 of `source`
};

// Never fails: syntax problems surface when the result is compiled. Generated parts are emitted
// under `#line 1 0` so only the BRDF's own text is reported against file lines. Each term the
// BRDF's text includes (its own includes first) is emitted once, before that text, and its
// include line becomes an empty line; an include that cannot be resolved becomes an `#error`
// line, so compiling reports it on the include's line of the file.
AssembledProgram assembleProgram(const ProgramSpec& spec);

// The default seed is the FNV-1a 64 offset basis (0xcbf29ce484222325).
uint64_t fnv1a64(const std::string& bytes, uint64_t seed = 14695981039346656037ull);

}  // namespace brdfa
