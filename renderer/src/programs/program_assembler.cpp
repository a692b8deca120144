// Program assembly in the fixed order of docs/design.md section 3.1. The only subtle part is line
// mapping: user text is emitted under `#line <file line> 1` and everything else under
// `#line <k> 0`, so glslang reports user errors against the submitted file (source string 1)
// and generated code against the assembled source (source string 0). With `#version 450`
// glslang gives the line after `#line N S` the number N (GLSL >= 3.30 semantics; checked by
// test_glsl_compiler.cpp).
#include "programs/program_assembler.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <mutex>
#include <set>
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

int countLines(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

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
  // A word list, grouped as the GLSL specification groups it.
  // clang-format off
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
  // clang-format on
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
    if (c == '\n') {
      lineStart = true;
      ++i;
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      ++i;
      continue;
    }
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
      if (braceDepth == 0 && parenDepth == 0 && prevWasIdent && j < n && text[j] == '(' && builtins.count(ident) &&
          std::find(out.begin(), out.end(), ident) == out.end())
        out.push_back(ident);
      prevWasIdent = true;
      continue;
    }
    if (c == '{')
      ++braceDepth;
    else if (c == '}')
      braceDepth = std::max(0, braceDepth - 1);
    else if (c == '(')
      ++parenDepth;
    else if (c == ')')
      parenDepth = std::max(0, parenDepth - 1);
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

// ---------------------------------------------------------------------------------------------
// Term includes (docs/design.md section 3.1). A term is trusted renderer code emitted in the
// generated region; only its include line stands in the user's text.

bool isTermNameChar(char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'; }

std::string_view trimmed(std::string_view s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

std::string includeError(std::string_view argument, const char* reason) {
  return "#include " + std::string(argument) + ": " + reason +
         "; a BRDF includes only shared terms, as #include \"terms/<name>.glsl\"";
}

std::mutex& defaultTermsMutex() {
  static std::mutex m;
  return m;
}

std::shared_ptr<const TermSources>& defaultTermsSlot() {
  static std::shared_ptr<const TermSources> slot = std::make_shared<const TermSources>();
  return slot;
}

// Resolves the include lines of the BRDF's text. Collects the included terms' texts in emission
// order, a term after the terms it includes, each once (`seen_` also ends include cycles).
class TermCollector {
 public:
  explicit TermCollector(const TermSources& terms) : terms_(terms) {}

  // `text` with each include line blanked, or replaced by an `#error` line when it does not
  // resolve; the line count stays, so the file's line numbers do too.
  std::string resolve(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    size_t at = 0;
    while (at < text.size()) {
      size_t end = text.find('\n', at);
      if (end == std::string::npos) end = text.size();
      const std::string_view line(text.data() + at, end - at);
      const TermInclude inc = parseTermInclude(line);
      if (!inc.isInclude)
        out.append(line);
      else if (!inc.error.empty())
        out += "#error malformed include - name a shared term as terms/NAME.glsl";
      else if (!terms_.count(inc.path))
        out += "#error unknown shared term " + termName(inc.path) + " - " + known();
      else
        add(inc.path);
      if (end < text.size()) out.push_back('\n');
      at = end + 1;
    }
    return out;
  }

  // The included terms' texts (their own include lines blanked), in emission order.
  const std::vector<std::string>& texts() const { return texts_; }

 private:
  static std::string termName(const std::string& path) { return path.substr(6, path.size() - 11); }

  std::string known() const {
    std::string names = "known terms are";
    for (const auto& entry : terms_) names += " " + termName(entry.first);
    return names;
  }

  void add(const std::string& path) {
    if (!seen_.insert(path).second) return;
    std::string text = resolve(terms_.at(path));  // adds the term's own includes first
    texts_.push_back(std::move(text));
  }

  const TermSources& terms_;
  std::set<std::string> seen_;
  std::vector<std::string> texts_;
};

}  // namespace

TermInclude parseTermInclude(std::string_view line) {
  TermInclude r;
  std::string_view t = trimmed(line);
  if (t.empty() || t.front() != '#') return r;
  t = trimmed(t.substr(1));
  if (!t.starts_with("include") || (t.size() > 7 && isIdentChar(t[7]))) return r;
  r.isInclude = true;
  std::string_view arg = t.substr(7);
  if (size_t comment = arg.find("//"); comment != std::string_view::npos) arg = arg.substr(0, comment);
  arg = trimmed(arg);
  if (arg.size() < 2 || arg.front() != '"' || arg.back() != '"') {
    r.error = includeError(arg, "expected a path in double quotes");
    return r;
  }
  const std::string_view path = arg.substr(1, arg.size() - 2);
  if (path.starts_with('/') || path.find("..") != std::string_view::npos || path.find('\\') != std::string_view::npos ||
      path.find(':') != std::string_view::npos) {
    r.error = includeError(arg, "the path may not leave shaders/lib/terms");
    return r;
  }
  const bool shaped = path.starts_with("terms/") && path.ends_with(".glsl") && path.size() > 11 &&
                      std::all_of(path.begin() + 6, path.end() - 5, isTermNameChar);
  if (!shaped) {
    r.error = includeError(arg, "not a shared term path");
    return r;
  }
  r.path = std::string(path);
  return r;
}

void setDefaultTermSources(TermSources terms) {
  auto shared = std::make_shared<const TermSources>(std::move(terms));
  std::lock_guard<std::mutex> lock(defaultTermsMutex());
  defaultTermsSlot() = std::move(shared);
}

std::shared_ptr<const TermSources> defaultTermSources() {
  std::lock_guard<std::mutex> lock(defaultTermsMutex());
  return defaultTermsSlot();
}

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
    // Included terms go before the renames and engine macros below, which are for the user's
    // text only; the include lines themselves become blank (or #error) lines of that text.
    const std::shared_ptr<const TermSources> fallback = spec.terms ? nullptr : defaultTermSources();
    TermCollector collector(spec.terms ? *spec.terms : *fallback);
    const std::string shader = collector.resolve(spec.brdf->shader);
    const std::string sampleShader = spec.brdf->hasSampler() ? collector.resolve(spec.brdf->sampleShader) : "";
    for (const std::string& text : collector.texts()) appendLine(s, text);

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

    appendUserText(s, shader, spec.brdf->shaderFirstLine);
    if (spec.brdf->hasSampler()) appendUserText(s, sampleShader, spec.brdf->sampleFirstLine);
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
