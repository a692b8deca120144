// Program assembly in the fixed order of DESIGN.md section 2. The only subtle part is line
// mapping: user text is emitted under `#line <file line> 1` and everything else under
// `#line <k> 0`, so glslang reports user errors against the submitted file (source string 1)
// and generated code against the assembled source (source string 0). With `#version 450`
// glslang gives the line after `#line N S` the number N (GLSL >= 3.30 semantics; checked by
// test_glsl_compiler.cpp).
#include "program_assembler.h"

#include <algorithm>
#include <cstring>

namespace brdfa {

namespace {

constexpr uint32_t alignUp(uint32_t value, uint32_t alignment) {
  return (value + alignment - 1) / alignment * alignment;
}

// std140: scalars (float, and bool stored as a uint) are 4-aligned; vec3 is 16-aligned with
// size 12, so a following scalar packs into its last 4 bytes.
uint32_t std140Alignment(ParamType type) { return type == ParamType::Color ? 16 : 4; }
uint32_t std140Size(ParamType type) { return type == ParamType::Color ? 12 : 4; }

const char* glslType(ParamType type) {
  switch (type) {
    case ParamType::Float: return "float";
    case ParamType::Color: return "vec3";
    case ParamType::Bool: return "bool";
  }
  return "float";
}

void appendLine(std::string& out, const std::string& text) {
  out += text;
  if (out.empty() || out.back() != '\n') out.push_back('\n');
}

int countLines(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

// `#line <k> 0` such that the line after the directive has its true number in `out`, which
// keeps generated-code messages readable against a dump of the assembled source.
void appendGeneratedLineDirective(std::string& out) {
  const int directiveLine = countLines(out) + 1;
  out += "#line " + std::to_string(directiveLine + 1) + " 0\n";
}

void appendUserText(std::string& out, const std::string& text, int firstLine) {
  out += "#line " + std::to_string(std::max(firstLine, 1)) + " 1\n";
  appendLine(out, text);
}

void writeFloat(std::vector<uint8_t>& bytes, uint32_t offset, float v) {
  std::memcpy(bytes.data() + offset, &v, sizeof v);
}

void writeUint(std::vector<uint8_t>& bytes, uint32_t offset, uint32_t v) {
  std::memcpy(bytes.data() + offset, &v, sizeof v);
}

}  // namespace

ParamBlockLayout layoutParams(const std::vector<BrdfParam>& params) {
  ParamBlockLayout layout;
  uint32_t offset = 0;
  for (const BrdfParam& p : params) {
    offset = alignUp(offset, std140Alignment(p.type));
    layout.entries.push_back({p.name, p.type, offset});
    offset += std140Size(p.type);
  }
  // A block's size is a multiple of its alignment (16 once a vec3 is present); rounding to 16
  // always also keeps the buffer binding range simple. An empty block still has a pad member.
  layout.size = std::max<uint32_t>(16, alignUp(offset, 16));
  return layout;
}

std::string ParamBlockLayout::glsl() const {
  std::string s = "layout(std140, set = 1, binding = 0) uniform BrdfParams {\n";
  if (entries.empty()) s += "  float brdfa_pad_;\n";
  for (const Entry& e : entries) s += std::string("  ") + glslType(e.type) + " " + e.name + ";\n";
  s += "};\n";
  return s;
}

std::vector<uint8_t> ParamBlockLayout::pack(const BrdfDefinition& brdf,
                                            const std::map<std::string, Vec3>& values) const {
  std::vector<uint8_t> bytes(size, 0);
  for (const Entry& e : entries) {
    if (e.offset + std140Size(e.type) > size) continue;  // a layout from elsewhere; stay in bounds
    Vec3 v{0, 0, 0};
    if (auto it = values.find(e.name); it != values.end())
      v = it->second;
    else if (const BrdfParam* p = brdf.findParam(e.name))
      v = p->defaultValue;
    switch (e.type) {
      case ParamType::Float: writeFloat(bytes, e.offset, v[0]); break;
      case ParamType::Bool: writeUint(bytes, e.offset, v[0] != 0.0f ? 1u : 0u); break;
      case ParamType::Color:
        for (uint32_t i = 0; i < 3; ++i) writeFloat(bytes, e.offset + 4 * i, v[i]);
        break;
    }
  }
  return bytes;
}

AssembledProgram assembleProgram(const ProgramSpec& spec) {
  static const std::vector<BrdfParam> kNoParams;
  const std::vector<BrdfParam>& params = spec.brdf ? spec.brdf->params : kNoParams;

  AssembledProgram program;
  program.params = layoutParams(params);
  std::string& s = program.source;

  // Prelude. Before any #line the whole text is source string 0, i.e. generated code.
  s += "#version 450\n";
  for (const std::string& d : spec.defines) s += "#define " + d + "\n";

  s += program.params.glsl();
  for (const std::string& chunk : spec.commonChunks) appendLine(s, chunk);

  if (spec.brdf) {
    appendUserText(s, spec.brdf->shader, spec.brdf->shaderFirstLine);
    if (spec.brdf->hasSampler())
      appendUserText(s, spec.brdf->sampleShader, spec.brdf->sampleFirstLine);
    appendGeneratedLineDirective(s);
  }
  appendLine(s, spec.integrator);

  program.hash = fnv1a64(s);
  return program;
}

uint64_t fnv1a64(const std::string& bytes, uint64_t seed) {
  uint64_t h = seed;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace brdfa
