// Parser for Disney BRDF Explorer's .brdf text format (docs/design.md section 3).
//
// Follows the Explorer's own reader (BRDFBase::loadBRDF) where it is well defined: '#' starts a
// comment outside GLSL, sections are `::begin X` ... `::end X` and cannot nest, parameter lines
// are `float name min max default`, `color name r g b`, `bool name 0|1`. Where the Explorer was
// silent (it ignored trailing garbage and left unparsed numbers uninitialised) we report an
// error on the offending line instead, so a typo never turns into a plausible-looking default.
#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "brdfa/brdf.h"

#include "programs/brdf_features.h"
#include "programs/program_assembler.h"

namespace brdfa {

const char* paramTypeName(ParamType type) {
  switch (type) {
    case ParamType::Float: return "float";
    case ParamType::Color: return "color";
    case ParamType::Bool: return "bool";
  }
  return "float";
}

const BrdfParam* BrdfDefinition::findParam(std::string_view name) const {
  for (const BrdfParam& p : params)
    if (p.name == name) return &p;
  return nullptr;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Small text helpers

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && isSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && isSpace(s.back())) s.remove_suffix(1);
  return s;
}

// Splits on '\n', dropping a trailing '\r' so CRLF files read like LF files. A final line
// without a newline is kept; the empty "line" after a final newline is not.
std::vector<std::string_view> splitLines(std::string_view text) {
  std::vector<std::string_view> lines;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    start = end + 1;
  }
  return lines;
}

std::string_view stripComment(std::string_view s) {
  size_t hash = s.find('#');
  return hash == std::string_view::npos ? s : s.substr(0, hash);
}

std::vector<std::string_view> tokenize(std::string_view s) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && isSpace(s[i])) ++i;
    size_t start = i;
    while (i < s.size() && !isSpace(s[i])) ++i;
    if (i > start) out.push_back(s.substr(start, i - start));
  }
  return out;
}

// Accepts what the Explorer's files use ("0", ".82", "1e-3", "+1"); rejects trailing junk,
// NaN and infinities.
bool parseNumber(std::string_view s, float& out) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  float v = 0;
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v)) return false;
  out = v;
  return true;
}

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

// ---------------------------------------------------------------------------------------------
// Parameter names become members of a uniform block, so they must be usable GLSL identifiers
// that cannot collide with the language or with names the integrator defines.

const std::unordered_set<std::string>& glslReservedWords() {
  static const std::unordered_set<std::string> words = [] {
    std::unordered_set<std::string> w = {
        // GLSL 4.50 keywords
        "const", "uniform", "buffer", "shared", "attribute", "varying", "coherent", "volatile", "restrict", "readonly",
        "writeonly", "atomic_uint", "layout", "centroid", "flat", "smooth", "noperspective", "patch", "sample",
        "invariant", "precise", "break", "continue", "do", "for", "while", "switch", "case", "default", "if", "else",
        "subroutine", "in", "out", "inout", "int", "void", "bool", "true", "false", "float", "double", "discard",
        "return", "uint", "lowp", "mediump", "highp", "precision", "struct",
        // reserved for future use
        "common", "partition", "active", "asm", "class", "union", "enum", "typedef", "template", "this", "resource",
        "goto", "inline", "noinline", "public", "static", "extern", "external", "interface", "long", "short", "half",
        "fixed", "unsigned", "superp", "input", "output", "hvec2", "hvec3", "hvec4", "fvec2", "fvec3", "fvec4",
        "sampler3DRect", "filter", "sizeof", "cast", "namespace", "using",
        // GL_KHR_vulkan_glsl
        "sampler", "samplerShadow", "subpassInput", "isubpassInput", "usubpassInput", "subpassInputMS",
        "isubpassInputMS", "usubpassInputMS",
        // shadow samplers
        "sampler1DShadow", "sampler2DShadow", "samplerCubeShadow", "sampler1DArrayShadow", "sampler2DArrayShadow",
        "sampler2DRectShadow", "samplerCubeArrayShadow"};
    for (const char* prefix : {"", "i", "u", "b", "d"})
      for (int n = 2; n <= 4; ++n) w.insert(std::string(prefix) + "vec" + std::to_string(n));
    for (const char* prefix : {"", "d"})
      for (int c = 2; c <= 4; ++c) {
        w.insert(std::string(prefix) + "mat" + std::to_string(c));
        for (int r = 2; r <= 4; ++r)
          w.insert(std::string(prefix) + "mat" + std::to_string(c) + "x" + std::to_string(r));
      }
    for (const char* prefix : {"", "i", "u"})
      for (const char* kind : {"sampler", "texture", "image"})
        for (const char* dim :
             {"1D", "2D", "3D", "Cube", "2DRect", "1DArray", "2DArray", "Buffer", "2DMS", "2DMSArray", "CubeArray"})
          w.insert(std::string(prefix) + kind + dim);
    return w;
  }();
  return words;
}

bool isReservedByIntegrator(std::string_view name) {
  static const std::array<std::string_view, 8> names = {"BRDF",      "sampleBRDF", "texCoord",  "iTexture0",
                                                        "iTexture1", "iTexture2",  "iTexture3", "BrdfParams"};
  return std::find(names.begin(), names.end(), name) != names.end();
}

bool isIdentifier(std::string_view s) {
  auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
  auto digit = [](char c) { return c >= '0' && c <= '9'; };
  if (s.empty() || !alpha(s.front())) return false;
  return std::all_of(s.begin(), s.end(), [&](char c) { return alpha(c) || digit(c); });
}

// Returns why `name` cannot be a parameter name, or nothing when it can.
std::optional<std::string> nameProblem(std::string_view name) {
  const std::string n(name);
  if (!isIdentifier(name))
    return "parameter name " + quoted(name) +
           " is not a GLSL identifier (letters, digits and '_', not starting with a digit)";
  if (glslReservedWords().count(n)) return "parameter name " + quoted(name) + " is a GLSL keyword or reserved word";
  if (name.starts_with("gl_")) return "parameter name " + quoted(name) + " starts with 'gl_', which GLSL reserves";
  if (name.starts_with("brdfa_"))
    return "parameter name " + quoted(name) + " starts with 'brdfa_', which the renderer reserves";
  if (name.find("__") != std::string_view::npos)
    return "parameter name " + quoted(name) + " contains '__', which GLSL reserves";
  if (isReservedByIntegrator(name)) return "parameter name " + quoted(name) + " is already defined by the renderer";
  return std::nullopt;
}

// ---------------------------------------------------------------------------------------------
// The Explorer's reader dropped every line starting with '#' before looking at sections, even
// inside the shader, so its files may put '#' comments there. Keep real preprocessor directives
// and blank such comment lines (keeping the line count, so line numbers still match).
bool isPreprocessorDirective(std::string_view trimmedLine) {
  std::string_view rest = trim(trimmedLine.substr(1));
  if (rest.empty()) return true;  // the null directive
  size_t end = 0;
  while (end < rest.size() && (std::isalpha(static_cast<unsigned char>(rest[end])))) ++end;
  static const std::array<std::string_view, 13> directives = {"define",    "undef",   "if",    "ifdef", "ifndef",
                                                              "else",      "elif",    "endif", "error", "pragma",
                                                              "extension", "version", "line"};
  return std::find(directives.begin(), directives.end(), rest.substr(0, end)) != directives.end();
}

enum class Section { None, Parameters, Shader, Sample, IsFunc, Unknown };

bool isIdentChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// True when `text` contains `vec3 <name> (` with `vec3` and `<name>` as whole words, i.e. the
// regex \bvec3\s+<name>\s*\( — a cheap check that the entry point is defined (it does not
// skip comments, which is fine for a friendly early error).
bool definesVec3Function(std::string_view text, std::string_view name) {
  auto skipSpace = [&](size_t i) {
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    return i;
  };
  for (size_t at = text.find("vec3"); at != std::string_view::npos; at = text.find("vec3", at + 1)) {
    if (at > 0 && isIdentChar(text[at - 1])) continue;
    size_t i = at + 4;
    const size_t nameStart = skipSpace(i);
    if (nameStart == i) continue;  // "vec3x" or "vec3(" — not a declaration
    if (text.substr(nameStart, name.size()) != name) continue;
    i = nameStart + name.size();
    if (i < text.size() && isIdentChar(text[i])) continue;
    i = skipSpace(i);
    if (i < text.size() && text[i] == '(') return true;
  }
  return false;
}

bool definesBrdf(std::string_view text) { return definesVec3Function(text, "BRDF"); }
bool definesSampler(std::string_view text) { return definesVec3Function(text, "sampleBRDF"); }
bool definesLegacyRender(std::string_view text) { return definesVec3Function(text, "render"); }

// The BRDFA Engine gave every BRDF the sliders iParameter0..8, floats in 0..1. A legacy file
// gets those it reads as parameters (declared in the parameter block like any other, so the
// file's unchanged text reads them); the engine's initial slider value is not recorded, 0.5
// (mid-range) is this project's choice.
void addLegacyParameters(BrdfDefinition& def) {
  for (int i = 0; i <= 8; ++i) {
    const std::string name = "iParameter" + std::to_string(i);
    if (def.findParam(name) || countWholeWords(def.shader, name) == 0) continue;
    BrdfParam p;
    p.name = name;
    p.type = ParamType::Float;
    p.min = 0.0f;
    p.max = 1.0f;
    p.defaultValue = {0.5f, 0.0f, 0.0f};
    def.params.push_back(std::move(p));
  }
}

// ---------------------------------------------------------------------------------------------

class Parser {
 public:
  Result<BrdfDefinition> run(std::string_view text);

 private:
  void error(int line, std::string message) { errors_.push_back(Diagnostic{line, 0, "error", std::move(message)}); }
  void warn(int line, std::string message) {
    def_.warnings.push_back(Diagnostic{line, 0, "warning", std::move(message)});
  }

  void handleDirective(const std::vector<std::string_view>& tokens, int line);
  void beginSection(std::string_view name, int line);
  void endSection(std::string_view name, int line);
  void handleOutsideLine(std::string_view text, int line);
  void handleClaimsLine(std::string_view comment, int line);
  void handleGlslLine(std::string_view raw, int line);
  void handleParamLine(std::string_view text, int line);
  bool parseFloatParam(const std::vector<std::string_view>& t, BrdfParam& p, int line);
  bool parseColorParam(const std::vector<std::string_view>& t, BrdfParam& p, int line);
  bool parseBoolParam(const std::vector<std::string_view>& t, BrdfParam& p, int line);
  bool parseLegacyWholeFile(std::string_view text);
  void finish(int lastLine);

  BrdfDefinition def_;
  std::vector<Diagnostic> errors_;
  Section section_ = Section::None;
  std::string sectionName_;
  int sectionLine_ = 0;
  int shaderSectionLine_ = 0;  // line of `::begin shader`, 0 when absent
  int sampleSectionLine_ = 0;
  std::string* glslTarget_ = nullptr;  // where lines of the open GLSL section go
};

void Parser::beginSection(std::string_view name, int line) {
  if (section_ != Section::None) {
    error(line, "'::begin " + std::string(name) + "' inside the '" + sectionName_ + "' section opened on line " +
                    std::to_string(sectionLine_) + "; close it with '::end " + sectionName_ + "' first");
    return;
  }
  sectionName_ = std::string(name);
  sectionLine_ = line;
  glslTarget_ = nullptr;
  if (name == "parameters") {
    section_ = Section::Parameters;
  } else if (name == "shader" || name == "sample") {
    const bool isShader = name == "shader";
    int& seen = isShader ? shaderSectionLine_ : sampleSectionLine_;
    if (seen != 0) {
      error(line, "second '::begin " + sectionName_ + "' section (the first is on line " + std::to_string(seen) + ")");
    } else {
      seen = line;
      glslTarget_ = isShader ? &def_.shader : &def_.sampleShader;
      (isShader ? def_.shaderFirstLine : def_.sampleFirstLine) = line + 1;
    }
    section_ = isShader ? Section::Shader : Section::Sample;
  } else if (name == "isFunc") {
    section_ = Section::IsFunc;
    warn(line,
         "the 'isFunc' section is ignored; importance sampling uses '::begin sample' "
         "with vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, "
         "out float pdf)");
  } else {
    section_ = Section::Unknown;
    warn(line, "unknown section " + quoted(name) + " is ignored");
  }
}

void Parser::endSection(std::string_view name, int line) {
  if (section_ == Section::None) {
    warn(line, "'::end " + std::string(name) + "' without a matching '::begin' is ignored");
    return;
  }
  if (name != sectionName_) {
    error(line, "'::end " + std::string(name) + "' does not close the '" + sectionName_ + "' section opened on line " +
                    std::to_string(sectionLine_));
    return;
  }
  section_ = Section::None;
  glslTarget_ = nullptr;
}

void Parser::handleDirective(const std::vector<std::string_view>& tokens, int line) {
  const bool begin = tokens[0] == "::begin";
  if (tokens.size() < 2) {
    error(line, quoted(tokens[0]) + " needs a section name, e.g. '" + std::string(tokens[0]) + " shader'");
    return;
  }
  if (tokens.size() > 2)
    warn(line, "extra text after '" + std::string(tokens[0]) + " " + std::string(tokens[1]) + "' is ignored");
  if (begin)
    beginSection(tokens[1], line);
  else
    endSection(tokens[1], line);
}

// `# claims: reciprocity, energy-conservation, non-negativity` (BrdfClaims). Other comments
// pass unread.
void Parser::handleClaimsLine(std::string_view comment, int line) {
  if (!comment.starts_with("claims:")) return;
  if (def_.claims.declared) {
    error(line, "a second claims line (the first is line " + std::to_string(def_.claims.line) + ")");
    return;
  }
  def_.claims.declared = true;
  def_.claims.line = line;
  std::string list(comment.substr(7));
  for (char& c : list)
    if (c == ',') c = ' ';
  for (std::string_view name : tokenize(list)) {
    if (name == "reciprocity")
      def_.claims.reciprocity = true;
    else if (name == "energy-conservation")
      def_.claims.energyConservation = true;
    else if (name == "non-negativity")
      def_.claims.nonNegativity = true;
    else if (name != "none")
      error(line, "unknown claim " + quoted(name) + " (known: reciprocity, energy-conservation, non-negativity, none)");
  }
}

void Parser::handleOutsideLine(std::string_view text, int line) {
  std::vector<std::string_view> tokens = tokenize(text);
  if (tokens.empty()) return;
  if (tokens[0] == "analytic") return;  // the Explorer's type line; optional here
  warn(line, "text outside any section is ignored: " + quoted(trim(text)));
}

void Parser::handleGlslLine(std::string_view raw, int line) {
  if (!glslTarget_) return;  // a duplicate section, already reported
  std::string_view t = trim(raw);
  // Not a '#' comment: `#include "terms/<name>.glsl"` pulls in a shared term (the assembler
  // resolves it; an unknown name fails to compile on this line). Any other include is an error
  // here, since dropping the line would only move the error elsewhere or hide it.
  const TermInclude include = parseTermInclude(t);
  if (include.isInclude && !include.error.empty()) error(line, include.error);
  if (!t.empty() && t.front() == '#' && !include.isInclude && !isPreprocessorDirective(t)) raw = {};
  glslTarget_->append(raw);
  glslTarget_->push_back('\n');
}

bool Parser::parseFloatParam(const std::vector<std::string_view>& t, BrdfParam& p, int line) {
  const size_t numbers = t.size() - 2;
  if (numbers < 2) {
    error(line, "float parameter " + quoted(p.name) + " needs 'float name min max default'");
    return false;
  }
  float v[3] = {0, 0, 0};
  for (size_t i = 0; i < std::min<size_t>(numbers, 3); ++i) {
    if (!parseNumber(t[2 + i], v[i])) {
      error(line, "float parameter " + quoted(p.name) + ": " + quoted(t[2 + i]) + " is not a number");
      return false;
    }
  }
  if (numbers == 2) {
    // `float name min max`: the meaning is clear, the default is not; start at min.
    v[2] = v[0];
    warn(line, "float parameter " + quoted(p.name) + " has no default; using its minimum");
  } else if (numbers > 3) {
    warn(line, "extra values after the default of " + quoted(p.name) + " are ignored");
  }
  if (v[0] > v[1]) {
    error(line, "float parameter " + quoted(p.name) + ": min " + std::string(t[2]) + " is greater than max " +
                    std::string(t[3]));
    return false;
  }
  if (v[2] < v[0] || v[2] > v[1]) {
    error(line, "float parameter " + quoted(p.name) + ": default " + std::string(t[4]) + " is outside [" +
                    std::string(t[2]) + ", " + std::string(t[3]) + "]");
    return false;
  }
  p.type = ParamType::Float;
  p.min = v[0];
  p.max = v[1];
  p.defaultValue = {v[2], 0, 0};
  return true;
}

bool Parser::parseColorParam(const std::vector<std::string_view>& t, BrdfParam& p, int line) {
  const size_t numbers = t.size() - 2;
  if (numbers < 3) {
    error(line, "color parameter " + quoted(p.name) + " needs 'color name r g b'");
    return false;
  }
  Vec3 c{0, 0, 0};
  for (size_t i = 0; i < 3; ++i) {
    if (!parseNumber(t[2 + i], c[i])) {
      error(line, "color parameter " + quoted(p.name) + ": " + quoted(t[2 + i]) + " is not a number");
      return false;
    }
    if (c[i] < 0.0f || c[i] > 1.0f) {
      error(line, "color parameter " + quoted(p.name) + ": component " + std::string(t[2 + i]) + " is outside [0, 1]");
      return false;
    }
  }
  if (numbers > 3) warn(line, "extra values after the color of " + quoted(p.name) + " are ignored");
  p.type = ParamType::Color;
  p.min = 0.0f;
  p.max = 1.0f;
  p.defaultValue = c;
  return true;
}

bool Parser::parseBoolParam(const std::vector<std::string_view>& t, BrdfParam& p, int line) {
  if (t.size() < 3) {
    error(line, "bool parameter " + quoted(p.name) + " needs 'bool name 0|1'");
    return false;
  }
  float v = 0;
  if (t[2] == "1" || t[2] == "true") {
    v = 1;
  } else if (t[2] == "0" || t[2] == "false") {
    v = 0;
  } else {
    error(line, "bool parameter " + quoted(p.name) + ": " + quoted(t[2]) + " is not 0 or 1");
    return false;
  }
  if (t.size() > 3) warn(line, "extra values after the value of " + quoted(p.name) + " are ignored");
  p.type = ParamType::Bool;
  p.min = 0.0f;
  p.max = 1.0f;
  p.defaultValue = {v, 0, 0};
  return true;
}

void Parser::handleParamLine(std::string_view text, int line) {
  std::vector<std::string_view> t = tokenize(stripComment(text));
  if (t.empty()) return;
  const std::string_view type = t[0];
  if (type != "float" && type != "color" && type != "bool") {
    error(line, "unknown parameter type " + quoted(type) + " (expected float, color or bool)");
    return;
  }
  if (t.size() < 2) {
    error(line, std::string(type) + " parameter has no name");
    return;
  }
  BrdfParam p;
  p.name = std::string(t[1]);
  p.line = line;
  if (auto problem = nameProblem(t[1])) {
    error(line, *problem);
    return;
  }
  if (const BrdfParam* first = def_.findParam(p.name)) {
    error(line, "parameter " + quoted(p.name) + " is already declared on line " + std::to_string(first->line));
    return;
  }
  bool ok = type == "float"   ? parseFloatParam(t, p, line)
            : type == "color" ? parseColorParam(t, p, line)
                              : parseBoolParam(t, p, line);
  if (ok) def_.params.push_back(std::move(p));
}

// Files written for the BRDFA Engine are plain GLSL with a `vec3 render(...)` entry point and no
// sections at all. Recognise them here; the legacy renderer decides what to do with them.
bool Parser::parseLegacyWholeFile(std::string_view text) {
  for (std::string_view l : splitLines(text))
    if (trim(l).starts_with("::begin")) return false;
  if (!definesLegacyRender(text) || definesBrdf(text)) return false;
  def_.format = BrdfFormat::Legacy;
  for (std::string_view l : splitLines(text)) {
    def_.shader.append(l);
    def_.shader.push_back('\n');
  }
  def_.shaderFirstLine = 1;
  addLegacyParameters(def_);
  return true;
}

void Parser::finish(int lastLine) {
  if (section_ != Section::None)
    warn(lastLine, "section '" + sectionName_ + "' opened on line " + std::to_string(sectionLine_) + " has no '::end " +
                       sectionName_ + "'; it ends at the end of the file");
  if (shaderSectionLine_ == 0) {
    error(0,
          "no '::begin shader' section: the file must define "
          "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)");
  } else if (!definesBrdf(def_.shader)) {
    if (definesLegacyRender(def_.shader)) {
      def_.format = BrdfFormat::Legacy;
      addLegacyParameters(def_);
    } else
      error(shaderSectionLine_,
            "the shader section does not define "
            "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)");
  }
  if (sampleSectionLine_ != 0 && !definesSampler(def_.sampleShader))
    error(sampleSectionLine_,
          "the sample section does not define vec3 sampleBRDF(vec2 u, "
          "vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, out float pdf)");
}

Result<BrdfDefinition> Parser::run(std::string_view text) {
  if (parseLegacyWholeFile(text)) return std::move(def_);

  const std::vector<std::string_view> lines = splitLines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line = static_cast<int>(i) + 1;
    const std::string_view raw = lines[i];
    const std::string_view t = trim(raw);
    if (t.starts_with("::begin") || t.starts_with("::end")) {
      std::vector<std::string_view> tokens = tokenize(stripComment(t));
      if (!tokens.empty() && (tokens[0] == "::begin" || tokens[0] == "::end")) {
        handleDirective(tokens, line);
        continue;
      }
    }
    switch (section_) {
      case Section::None:
        if (t.starts_with("#")) handleClaimsLine(trim(t.substr(1)), line);
        handleOutsideLine(stripComment(raw), line);
        break;
      case Section::Parameters: handleParamLine(raw, line); break;
      case Section::Shader:
      case Section::Sample: handleGlslLine(raw, line); break;
      case Section::IsFunc:
      case Section::Unknown: break;  // ignored, warned at its `::begin`
    }
  }
  finish(static_cast<int>(lines.size()));

  if (errors_.empty()) return std::move(def_);
  std::string message = "invalid BRDF file: ";
  if (errors_[0].line > 0) message += "line " + std::to_string(errors_[0].line) + ": ";
  message += errors_[0].message;
  if (errors_.size() > 1) message += " (and " + std::to_string(errors_.size() - 1) + " more)";
  Error e = makeError(ErrorCode::CompileError, std::move(message));
  e.diagnostics = std::move(errors_);
  return e;
}

}  // namespace

Result<BrdfDefinition> parseBrdf(std::string_view text) {
  Parser parser;
  return parser.run(text);
}

}  // namespace brdfa
