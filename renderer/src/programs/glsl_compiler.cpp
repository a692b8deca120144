// GLSL -> SPIR-V with glslang in process, and translation of glslang's info log into
// Diagnostics against the submitted .brdf file (see glsl_compiler.h for the line contract).
#include "programs/glsl_compiler.h"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>
#include <glslang/build_info.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <string_view>

namespace brdfa {

namespace {

constexpr int kUserSourceString = 1;  // the string number the assembler gives user text

void initializeGlslangOnce() {
  static std::once_flag once;
  // Process-wide and never finalized: compiles may happen until exit.
  std::call_once(once, [] { glslang::InitializeProcess(); });
}

EShLanguage toGlslangStage(ShaderStage stage) {
  switch (stage) {
    case ShaderStage::Compute: return EShLangCompute;
    case ShaderStage::Vertex: return EShLangVertex;
    case ShaderStage::Fragment: return EShLangFragment;
  }
  return EShLangCompute;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// glslang writes "'token' : message"; with no token it writes "'' :  message", which reads
// better without the empty quotes.
std::string cleanMessage(std::string_view text) {
  text = trim(text);
  if (text.starts_with("'' :")) text = trim(text.substr(4));
  return std::string(text);
}

// A message as glslang reported it, before mapping to the user's file.
struct RawMessage {
  std::string severity;  // "error" | "warning"
  bool located = false;
  int sourceString = 0;
  int line = 0;
  int column = 0;
  std::string text;
};

// Reads an unsigned decimal at `s[pos]` followed by `end`; advances `pos` past `end`.
bool readNumberThen(std::string_view s, size_t& pos, char end, int& out) {
  size_t i = pos;
  long v = 0;
  while (i < s.size() && s[i] >= '0' && s[i] <= '9' && v < 100000000) v = v * 10 + (s[i++] - '0');
  if (i == pos || i >= s.size() || s[i] != end) return false;
  out = static_cast<int>(v);
  pos = i + 1;
  return true;
}

bool isSummaryLine(std::string_view text) {
  // "ERROR: 2 compilation errors.  No code generated." counts, it does not diagnose.
  size_t pos = 0;
  int n = 0;
  return readNumberThen(text, pos, ' ', n) && text.substr(pos).starts_with("compilation error");
}

bool isNoise(const RawMessage& m) {
  // Emitted after the first error when glslang gives up; the real cause is already listed.
  return isSummaryLine(m.text) || m.text == "compilation terminated";
}

// Splits off "<string>:<line>: " or "<string>:<line>:<column>: " at the start of `rest`.
void readLocation(std::string_view& rest, RawMessage& msg) {
  size_t pos = 0;
  int str = 0, line = 0, column = 0;
  if (!readNumberThen(rest, pos, ':', str) || !readNumberThen(rest, pos, ':', line)) return;
  size_t withColumn = pos;
  if (readNumberThen(rest, withColumn, ':', column)) pos = withColumn;
  if (pos >= rest.size() || rest[pos] != ' ') return;
  msg.located = true;
  msg.sourceString = str;
  msg.line = line;
  msg.column = pos == withColumn ? column : 0;
  rest.remove_prefix(pos + 1);
}

// Parses lines such as
//   ERROR: 1:9: 'x' : undeclared identifier
//   WARNING: 0:3: '#extension' : extension not supported: GL_EXT_foo
//   ERROR: Linking compute stage: Missing entry point: Each stage requires one entry point
// Lines without a known prefix continue the previous message.
std::vector<RawMessage> parseInfoLog(std::string_view log) {
  static constexpr std::pair<std::string_view, const char*> kPrefixes[] = {{"ERROR: ", "error"},
                                                                           {"WARNING: ", "warning"},
                                                                           {"INTERNAL ERROR: ", "error"},
                                                                           {"UNIMPLEMENTED: ", "error"},
                                                                           {"NOTE: ", "warning"}};
  std::vector<RawMessage> out;
  size_t start = 0;
  while (start < log.size()) {
    size_t end = log.find('\n', start);
    if (end == std::string_view::npos) end = log.size();
    const std::string_view line = trim(log.substr(start, end - start));
    start = end + 1;
    if (line.empty()) continue;

    const auto* prefix = std::find_if(std::begin(kPrefixes), std::end(kPrefixes),
                                      [&](const auto& p) { return line.starts_with(p.first); });
    if (prefix == std::end(kPrefixes)) {
      if (!out.empty()) out.back().text += " " + std::string(line);
      continue;
    }
    RawMessage msg;
    msg.severity = prefix->second;
    std::string_view rest = line.substr(prefix->first.size());
    readLocation(rest, msg);
    msg.text = cleanMessage(rest);
    if (!isNoise(msg)) out.push_back(std::move(msg));
  }
  return out;
}

// User text keeps its file line; anything else is reported as generated code at line 0, with
// its assembled-source line kept in the text for whoever debugs the templates.
Diagnostic toDiagnostic(const RawMessage& m) {
  Diagnostic d;
  d.severity = m.severity;
  if (m.located && m.sourceString == kUserSourceString) {
    d.line = m.line;
    d.column = m.column;
    d.message = m.text;
  } else if (m.located) {
    d.message = "in generated code: line " + std::to_string(m.line) + ": " + m.text;
  } else {
    d.message = m.text;  // link-stage and other unlocated messages
  }
  return d;
}

// User lines first, in line order; then the rest in the order glslang reported them.
std::vector<Diagnostic> toDiagnostics(const std::vector<RawMessage>& raw) {
  std::vector<RawMessage> user, other;
  for (const RawMessage& m : raw) (m.located && m.sourceString == kUserSourceString ? user : other).push_back(m);
  std::stable_sort(user.begin(), user.end(), [](const RawMessage& a, const RawMessage& b) { return a.line < b.line; });
  std::vector<Diagnostic> out;
  for (const RawMessage& m : user) out.push_back(toDiagnostic(m));
  for (const RawMessage& m : other) out.push_back(toDiagnostic(m));
  return out;
}

std::vector<Diagnostic> warningsOf(const std::vector<Diagnostic>& all) {
  std::vector<Diagnostic> w;
  for (const Diagnostic& d : all)
    if (d.severity == "warning") w.push_back(d);
  return w;
}

Error compileError(std::vector<Diagnostic> diagnostics, const std::string& fallback) {
  std::string message = "GLSL compilation failed";
  auto first =
      std::find_if(diagnostics.begin(), diagnostics.end(), [](const Diagnostic& d) { return d.severity == "error"; });
  if (first != diagnostics.end()) {
    message += ": ";
    if (first->line > 0) message += "line " + std::to_string(first->line) + ": ";
    message += first->message;
  } else {
    // glslang failed without a parsable message; keep its raw log rather than nothing.
    message += ": " + fallback;
    diagnostics.push_back(Diagnostic{0, 0, "error", fallback});
  }
  Error e = makeError(ErrorCode::CompileError, std::move(message));
  e.diagnostics = std::move(diagnostics);
  return e;
}

std::mutex& compileMutex() {
  static std::mutex m;
  return m;
}

Result<SpirvBinary> compileLocked(ShaderStage stage, const std::string& source) {
  const EShLanguage lang = toGlslangStage(stage);
  const auto messages = static_cast<EShMessages>(EShMsgSpvRules | EShMsgVulkanRules);

  glslang::TShader shader(lang);
  const char* text = source.c_str();
  shader.setStrings(&text, 1);
  shader.setEnvInput(glslang::EShSourceGlsl, lang, glslang::EShClientVulkan, 100);
  shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_1);
  shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_3);

  const bool parsed = shader.parse(GetDefaultResources(), 450, false, messages);
  std::vector<RawMessage> raw = parseInfoLog(shader.getInfoLog());
  if (!parsed)
    return compileError(toDiagnostics(raw), trim(shader.getInfoLog()).empty() ? "parse failed" : shader.getInfoLog());

  glslang::TProgram program;
  program.addShader(&shader);
  const bool linked = program.link(messages);
  std::vector<RawMessage> linkRaw = parseInfoLog(program.getInfoLog());
  raw.insert(raw.end(), linkRaw.begin(), linkRaw.end());
  if (!linked)
    return compileError(toDiagnostics(raw), trim(program.getInfoLog()).empty() ? "link failed" : program.getInfoLog());

  SpirvBinary out;
  spv::SpvBuildLogger logger;
  glslang::SpvOptions options;
  options.generateDebugInfo = false;
  options.disableOptimizer = true;
  options.validate = false;
  glslang::GlslangToSpv(*program.getIntermediate(lang), out.words, &logger, &options);
  out.warnings = warningsOf(toDiagnostics(raw));
  if (const std::string spvLog = logger.getAllMessages(); !trim(spvLog).empty())
    out.warnings.push_back(Diagnostic{0, 0, "warning", std::string(trim(spvLog))});
  if (out.words.empty()) return makeError(ErrorCode::Internal, "glslang produced no SPIR-V for a valid program");
  return out;
}

}  // namespace

Result<SpirvBinary> compileGlsl(ShaderStage stage, const std::string& source) {
  initializeGlslangOnce();
  try {
    std::lock_guard<std::mutex> lock(compileMutex());
    const auto start = std::chrono::steady_clock::now();
    Result<SpirvBinary> result = compileLocked(stage, source);
    if (result.ok())
      result->compileMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  } catch (const std::exception& e) {
    // glslang can throw (e.g. std::bad_alloc); nothing may escape the renderer's API.
    return makeError(ErrorCode::Internal, std::string("glslang threw: ") + e.what());
  } catch (...) {
    return makeError(ErrorCode::Internal, "glslang threw an unknown exception");
  }
}

std::string compilerVersion() {
  // Both the headers we built against and the library we run with, plus our fixed targets:
  // any change means previously cached SPIR-V may differ.
  return "glslang " + std::to_string(GLSLANG_VERSION_MAJOR) + "." + std::to_string(GLSLANG_VERSION_MINOR) + "." +
         std::to_string(GLSLANG_VERSION_PATCH) + GLSLANG_VERSION_FLAVOR + " (" + glslang::GetGlslVersionString() +
         ", tool " + std::to_string(glslang::GetKhronosToolId()) + "); vulkan1.1 spirv1.3";
}

}  // namespace brdfa
