// Program assembly in the fixed order of docs/design.md section 2. The only subtle part is line
// mapping: user text is emitted under `#line <file line> 1` and everything else under
// `#line <k> 0`, so glslang reports user errors against the submitted file (source string 1)
// and generated code against the assembled source (source string 0). With `#version 450`
// glslang gives the line after `#line N S` the number N (GLSL >= 3.30 semantics; checked by
// test_glsl_compiler.cpp).
#include "programs/program_assembler.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <unordered_set>

#include "programs/brdf_features.h"

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

// Names of GLSL built-in functions (GLSL 4.50 plus the legacy texture names and noise). The
// Explorer compiled its files as old desktop GLSL, where a user function with a built-in's name
// hid the built-in (its shipped files define their own `reflect` and `smoothstep`); glslang
// under `#version 450` rejects that. Renaming such user functions with a macro keeps the user
// text unchanged and gives the old meaning: every use of the name in the user's sections is
// the user's function. Renaming a name that is not a built-in would also be harmless.
const std::unordered_set<std::string>& builtinFunctionNames() {
  static const std::unordered_set<std::string> names = {
      // angle and trigonometry, exponential, common
      "radians", "degrees", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh",
      "asinh", "acosh", "atanh", "pow", "exp", "log", "exp2", "log2", "sqrt", "inversesqrt",
      "abs", "sign", "floor", "trunc", "round", "roundEven", "ceil", "fract", "mod", "modf",
      "min", "max", "clamp", "mix", "step", "smoothstep", "isnan", "isinf", "floatBitsToInt",
      "floatBitsToUint", "intBitsToFloat", "uintBitsToFloat", "fma", "frexp", "ldexp",
      // packing
      "packUnorm2x16", "packSnorm2x16", "packUnorm4x8", "packSnorm4x8", "unpackUnorm2x16",
      "unpackSnorm2x16", "unpackUnorm4x8", "unpackSnorm4x8", "packHalf2x16", "unpackHalf2x16",
      "packDouble2x32", "unpackDouble2x32",
      // geometric, matrix, vector relational
      "length", "distance", "dot", "cross", "normalize", "faceforward", "reflect", "refract",
      "ftransform", "matrixCompMult", "outerProduct", "transpose", "determinant", "inverse",
      "lessThan", "lessThanEqual", "greaterThan", "greaterThanEqual", "equal", "notEqual", "any",
      "all", "not",
      // integer
      "uaddCarry", "usubBorrow", "umulExtended", "imulExtended", "bitfieldExtract",
      "bitfieldInsert", "bitfieldReverse", "bitCount", "findLSB", "findMSB",
      // texture
      "textureSize", "textureQueryLod", "textureQueryLevels", "textureSamples", "texture",
      "textureProj", "textureLod", "textureOffset", "texelFetch", "texelFetchOffset",
      "textureProjOffset", "textureLodOffset", "textureProjLod", "textureProjLodOffset",
      "textureGrad", "textureGradOffset", "textureProjGrad", "textureProjGradOffset",
      "textureGather", "textureGatherOffset", "textureGatherOffsets", "texture1D", "texture1DProj",
      "texture1DLod", "texture1DProjLod", "texture2D", "texture2DProj", "texture2DLod",
      "texture2DProjLod", "texture3D", "texture3DProj", "texture3DLod", "texture3DProjLod",
      "textureCube", "textureCubeLod", "shadow1D", "shadow2D", "shadow1DProj", "shadow2DProj",
      "shadow1DLod", "shadow2DLod", "shadow1DProjLod", "shadow2DProjLod",
      // derivatives, interpolation, noise
      "dFdx", "dFdy", "fwidth", "dFdxFine", "dFdyFine", "fwidthFine", "dFdxCoarse", "dFdyCoarse",
      "fwidthCoarse", "interpolateAtCentroid", "interpolateAtSample", "interpolateAtOffset",
      "noise1", "noise2", "noise3", "noise4",
      // atomics, images, synchronisation
      "atomicCounterIncrement", "atomicCounterDecrement", "atomicCounter", "atomicAdd",
      "atomicMin", "atomicMax", "atomicAnd", "atomicOr", "atomicXor", "atomicExchange",
      "atomicCompSwap", "imageSize", "imageSamples", "imageLoad", "imageStore", "imageAtomicAdd",
      "imageAtomicMin", "imageAtomicMax", "imageAtomicAnd", "imageAtomicOr", "imageAtomicXor",
      "imageAtomicExchange", "imageAtomicCompSwap", "barrier", "memoryBarrier",
      "memoryBarrierAtomicCounter", "memoryBarrierBuffer", "memoryBarrierShared",
      "memoryBarrierImage", "groupMemoryBarrier", "EmitVertex", "EndPrimitive",
      "EmitStreamVertex", "EndStreamPrimitive",
  };
  return names;
}

bool isIdentStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool isIdentChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Appends to `out` the names of functions that `text` declares or defines at file scope
// (`<type> <name> (` outside any braces) and that are GLSL built-in function names.
// Comments and preprocessor lines are skipped; a call such as `x = reflect(a, b);` is not a
// declaration because the token before the name is not an identifier (a type).
void collectBuiltinOverrides(const std::string& text, std::vector<std::string>& out) {
  const auto& builtins = builtinFunctionNames();
  int braceDepth = 0, parenDepth = 0;
  bool prevWasIdent = false;  // the previous token was an identifier (a type name, say)
  size_t i = 0;
  const size_t n = text.size();
  bool lineStart = true;
  while (i < n) {
    char c = text[i];
    if (c == '\n') { lineStart = true; ++i; continue; }
    if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') { ++i; continue; }
    if (c == '/' && i + 1 < n && text[i + 1] == '/') {
      while (i < n && text[i] != '\n') ++i;
      continue;
    }
    if (c == '/' && i + 1 < n && text[i + 1] == '*') {
      size_t end = text.find("*/", i + 2);
      i = end == std::string::npos ? n : end + 2;
      continue;
    }
    if (c == '#' && lineStart) {  // preprocessor line (with backslash continuations)
      while (i < n && text[i] != '\n') {
        if (text[i] == '\\' && i + 1 < n && text[i + 1] == '\n') ++i;
        ++i;
      }
      prevWasIdent = false;
      continue;
    }
    lineStart = false;
    if (isIdentStart(c)) {
      size_t start = i;
      while (i < n && isIdentChar(text[i])) ++i;
      std::string ident = text.substr(start, i - start);
      size_t j = i;
      while (j < n && (text[j] == ' ' || text[j] == '\t' || text[j] == '\r' || text[j] == '\n')) ++j;
      if (braceDepth == 0 && parenDepth == 0 && prevWasIdent && j < n && text[j] == '(' &&
          builtins.count(ident) && std::find(out.begin(), out.end(), ident) == out.end())
        out.push_back(ident);
      prevWasIdent = true;
      continue;
    }
    if (c == '{') ++braceDepth;
    else if (c == '}') braceDepth = std::max(0, braceDepth - 1);
    else if (c == '(') ++parenDepth;
    else if (c == ')') parenDepth = std::max(0, parenDepth - 1);
    // `]` closes an array return type (`float[2] f(`); keep it acting like a type name.
    prevWasIdent = (c == ']');
    ++i;
  }
}

// Appends to `out` every NAME of a `# define NAME` line in `text` (conditional ones too:
// #undef of a name never defined is harmless). Preprocessor lines are whole lines.
void collectDefinedMacros(const std::string& text, std::vector<std::string>& out) {
  size_t at = 0;
  while (at < text.size()) {
    size_t end = text.find('\n', at);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + at, end - at);
    at = end + 1;
    size_t i = line.find_first_not_of(" \t");
    if (i == std::string_view::npos || line[i] != '#') continue;
    i = line.find_first_not_of(" \t", i + 1);
    if (i == std::string_view::npos || line.substr(i, 6) != "define") continue;
    i = line.find_first_not_of(" \t", i + 6);
    if (i == std::string_view::npos || !isIdentStart(line[i])) continue;
    size_t j = i;
    while (j < line.size() && isIdentChar(line[j])) ++j;
    std::string name(line.substr(i, j - i));
    if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(std::move(name));
  }
}

// The names the BRDFA Engine's host shader defines for a render() file, with the engine's text.
// The engine compiled each .brdf file appended to that shader (Mohido/BRDFA_Engine at commit
// 97f1b36eb3b864d242055928a29cc76c31274a5b: BRDFA_Engine/src/brdfa_engine.cpp,
// loadPipelines(), concatenates shaders/main.frag and the file's text; main.frag opens with
// `#define PI 3.14159265359` and `#define LI 8.`, LI being the light intensity its earlier host
// multiplied the skybox by). Here each is defined only where the file gives the name no meaning
// of its own (declaresName): a file's identical `#define PI 3.14159265359` compiled in the
// engine and still does, and a different #define or a `const float PI = ...`, which the engine
// rejected, compiles with the file's own meaning.
struct EngineMacro {
  const char* name;
  const char* value;
};
constexpr EngineMacro kEngineMacros[] = {{"PI", "3.14159265359"}, {"LI", "8."}};

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
  for (const std::string& chunk : spec.userChunks) appendLine(s, chunk);

  if (spec.brdf) {
    // User functions named like GLSL built-ins (see builtinFunctionNames) are renamed for the
    // user's sections only: the #defines sit in the generated region before the first user
    // `#line`, so user line numbers are untouched, and are #undef'd before the integrator.
    std::vector<std::string> renamed;
    collectBuiltinOverrides(spec.brdf->shader, renamed);
    if (spec.brdf->hasSampler()) collectBuiltinOverrides(spec.brdf->sampleShader, renamed);
    for (const std::string& name : renamed) s += "#define " + name + " brdfa_user_" + name + "\n";
    // A BRDFA Engine file sees the names its engine defined (kEngineMacros), in the generated
    // region like the renames, and they end with its text like its own macros.
    std::vector<std::string> macros;
    if (spec.brdf->format == BrdfFormat::Legacy) {
      const std::string userText = spec.brdf->shader + "\n" + spec.brdf->sampleShader;
      for (const EngineMacro& m : kEngineMacros) {
        if (declaresName(userText, m.name)) continue;
        s += std::string("#define ") + m.name + " " + m.value + "\n";
        macros.emplace_back(m.name);
      }
    }

    appendUserText(s, spec.brdf->shader, spec.brdf->shaderFirstLine);
    if (spec.brdf->hasSampler())
      appendUserText(s, spec.brdf->sampleShader, spec.brdf->sampleFirstLine);
    for (const std::string& name : renamed) s += "#undef " + name + "\n";
    // The BRDF's own macros end with its text: none may rewrite the integrator's code.
    collectDefinedMacros(spec.brdf->shader, macros);
    if (spec.brdf->hasSampler()) collectDefinedMacros(spec.brdf->sampleShader, macros);
    for (const std::string& name : macros) s += "#undef " + name + "\n";
    appendGeneratedLineDirective(s);
  }
  for (const std::string& chunk : spec.commonChunks) appendLine(s, chunk);
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
