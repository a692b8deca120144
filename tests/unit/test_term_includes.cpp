// Shared term includes (`#include "terms/<name>.glsl"`, docs/design.md section 3): the include
// line's syntax, resolution by the assembler (each term once, before the BRDF's text), errors on
// the include's own line, user line numbers after an include, and the built-in library, which
// uses them, compiling on the device.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "brdfa/renderer.h"
#include "device_test.h"
#include "programs/glsl_compiler.h"
#include "programs/program_assembler.h"
#include "programs/shader_sources.h"

namespace brdfa {
namespace {

const std::string kShaderDir = std::string(BRDFA_SOURCE_DIR) + "/shaders";

// A compute kernel that calls BRDF() once, as the integrators do.
constexpr const char* kIntegrator = R"(
layout(local_size_x = 1) in;
layout(std430, set = 0, binding = 1) buffer Out { vec4 value; } outBuf;
void main() {
  outBuf.value = vec4(BRDF(vec3(0, 0, 1), vec3(0, 0.6, 0.8), vec3(0, 0, 1), vec3(1, 0, 0), vec3(0, 1, 0)), 1.0);
}
)";

const ShaderSources& sources() {
  static const ShaderSources s = [] {
    auto r = ShaderSources::load(kShaderDir);
    EXPECT_TRUE(r.ok());
    return r.ok() ? std::move(r.value()) : ShaderSources{};
  }();
  return s;
}

AssembledProgram assemble(const BrdfDefinition& def) {
  ProgramSpec spec;
  spec.brdf = &def;
  spec.terms = &sources().terms();
  spec.userChunks = {sources().get("lib/brdf_inputs.glsl")};
  spec.integrator = kIntegrator;
  return assembleProgram(spec);
}

// Parses `text` and compiles it with kIntegrator; parse errors come back as they are.
Result<SpirvBinary> compileText(const std::string& text) {
  Result<BrdfDefinition> def = parseBrdf(text);
  if (!def.ok()) return def.takeError();
  return compileGlsl(ShaderStage::Compute, assemble(def.value()).source);
}

size_t occurrences(const std::string& haystack, const std::string& needle) {
  size_t n = 0;
  for (size_t at = haystack.find(needle); at != std::string::npos; at = haystack.find(needle, at + 1)) ++n;
  return n;
}

// A file whose line 5 holds `includeLine` and whose BRDF (lines 6-8, `body` on line 7) uses
// D_GGX by default.
std::string fileWithInclude(const std::string& includeLine, const std::string& body = "return vec3(D_GGX(0.9, a));") {
  return "::begin parameters\n"   // 1
         "float a 0.001 1 0.3\n"  // 2
         "::end parameters\n"     // 3
         "::begin shader\n"       // 4
         + includeLine +
         "\n"                                                     // 5
         "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n"  // 6
         "  " +
         body +
         "\n"               // 7
         "}\n"              // 8
         "::end shader\n";  // 9
}

const Diagnostic& firstError(const Error& e) {
  static const Diagnostic none{-1, 0, "none", "no diagnostics"};
  auto it = std::find_if(e.diagnostics.begin(), e.diagnostics.end(),
                         [](const Diagnostic& d) { return d.severity == "error"; });
  return it == e.diagnostics.end() ? none : *it;
}

TEST(TermIncludes, ParsesTheIncludeLine) {
  TermInclude ok = parseTermInclude("  #  include \"terms/d_ggx.glsl\"   // the GGX D");
  EXPECT_TRUE(ok.isInclude);
  EXPECT_EQ(ok.error, "");
  EXPECT_EQ(ok.path, "terms/d_ggx.glsl");
  for (const char* notInclude : {"#define X 1", "float x;", "#includes \"terms/d_ggx.glsl\"", ""})
    EXPECT_FALSE(parseTermInclude(notInclude).isInclude) << notInclude;
  for (const char* bad :
       {"#include \"../d_ggx.glsl\"", "#include \"terms/../bindings.glsl\"", "#include \"/etc/passwd\"",
        "#include <terms/d_ggx.glsl>", "#include", "#include \"terms/D_GGX.glsl\"", "#include \"bindings.glsl\"",
        "#include \"terms/.glsl\"", "#include \"terms/a/b.glsl\""}) {
    TermInclude r = parseTermInclude(bad);
    EXPECT_TRUE(r.isInclude) << bad;
    EXPECT_NE(r.error, "") << bad;
    EXPECT_EQ(r.path, "") << bad;
  }
}

TEST(TermIncludes, EveryTermFileCompilesAlone) {
  ASSERT_FALSE(sources().terms().empty());
  for (const auto& [path, text] : sources().terms()) {
    SCOPED_TRACE(path);
    Result<SpirvBinary> r = compileText(fileWithInclude("#include \"" + path + "\"", "return vec3(1.0);"));
    EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  }
}

TEST(TermIncludes, IncludeResolvesBeforeTheBrdfTextAndCompiles) {
  const std::string text = fileWithInclude("#include \"terms/d_ggx.glsl\"");
  Result<BrdfDefinition> def = parseBrdf(text);
  ASSERT_TRUE(def.ok()) << def.error().message;
  const std::string src = assemble(def.value()).source;
  EXPECT_EQ(src.find("#include"), std::string::npos) << "no include line reaches glslang";
  const size_t term = src.find("float D_GGX(");
  const size_t user = src.find("vec3 BRDF(");
  ASSERT_NE(term, std::string::npos);
  EXPECT_LT(term, src.find("#line 5 1")) << "terms come before the user's text";
  EXPECT_LT(src.find("brdfa_PI ="), term) << "a term's own include comes before it";
  EXPECT_LT(src.find("#line 5 1"), user);
  Result<SpirvBinary> r = compileGlsl(ShaderStage::Compute, src);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
}

TEST(TermIncludes, IncludedTwiceIsEmittedOnce) {
  // d_ggx and d_beckmann both include constants.glsl; d_ggx is also named twice.
  const std::string text =
      "::begin shader\n"
      "#include \"terms/d_ggx.glsl\"\n"
      "#include \"terms/d_beckmann.glsl\"\n"
      "const float PI = 3.14159265358979323846;\n"
      "#include \"terms/d_ggx.glsl\"\n"
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n"
      "  return vec3(D_GGX(0.9, 0.3) + D_Beckmann(0.9, 0.3)) / PI;\n"
      "}\n"
      "::end shader\n"
      "::begin sample\n"
      "#include \"terms/d_ggx.glsl\"\n"
      "vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, out float pdf) {\n"
      "  L = N; pdf = D_GGX(1.0, 0.3); return BRDF(L, V, N, X, Y);\n"
      "}\n"
      "::end sample\n";
  Result<BrdfDefinition> def = parseBrdf(text);
  ASSERT_TRUE(def.ok()) << def.error().message;
  const std::string src = assemble(def.value()).source;
  EXPECT_EQ(occurrences(src, "float D_GGX("), 1u);
  EXPECT_EQ(occurrences(src, "float D_Beckmann("), 1u);
  EXPECT_EQ(occurrences(src, "const float brdfa_PI"), 1u);
  Result<SpirvBinary> r = compileGlsl(ShaderStage::Compute, src);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
}

TEST(TermIncludes, UnknownTermFailsOnTheIncludeLine) {
  Result<SpirvBinary> r = compileText(fileWithInclude("#include \"terms/d_nonesuch.glsl\""));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::CompileError);
  EXPECT_EQ(firstError(r.error()).line, 5);
  EXPECT_NE(firstError(r.error()).message.find("unknown shared term d_nonesuch"), std::string::npos)
      << firstError(r.error()).message;
}

TEST(TermIncludes, PathsOutsideTheTermsFolderFailOnTheIncludeLine) {
  for (const char* include : {"#include \"../lib/bindings.glsl\"", "#include \"terms/../bindings.glsl\"",
                              "#include \"/etc/hostname\"", "#include <terms/d_ggx.glsl>"}) {
    SCOPED_TRACE(include);
    Result<SpirvBinary> r = compileText(fileWithInclude(include));
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::CompileError);
    EXPECT_EQ(firstError(r.error()).line, 5);
    EXPECT_NE(firstError(r.error()).message.find("terms/<name>.glsl"), std::string::npos);
  }
}

TEST(TermIncludes, LegacyFileIncludesResolveAndFailOnTheirLine) {
  // A BRDFA Engine file is bare GLSL with no sections (the parser does not look at its lines):
  // the assembler resolves its includes alike and reports a bad one on its line.
  const std::string legacy =
      "#include \"terms/f_schlick.glsl\"\n"  // 1
      "%s\n"                                 // 2
      "vec3 render(vec3 L, vec3 N, vec3 V, vec2 textureCord, mat3 worldToLocal) {\n"
      "  return F_Schlick(dot(N, V), vec3(0.04));\n"
      "}\n";
  auto withLine2 = [&](const std::string& line2) {
    std::string s = legacy;
    return s.replace(s.find("%s"), 2, line2);
  };
  Result<BrdfDefinition> good = parseBrdf(withLine2("// nothing"));
  ASSERT_TRUE(good.ok());
  ASSERT_EQ(good->format, BrdfFormat::Legacy);
  EXPECT_EQ(occurrences(assemble(good.value()).source, "vec3 F_Schlick("), 1u);
  for (const char* bad : {"#include \"../kernels/shade.comp.glsl\"", "#include \"terms/nope.glsl\""}) {
    Result<BrdfDefinition> def = parseBrdf(withLine2(bad));
    ASSERT_TRUE(def.ok());
    Result<SpirvBinary> r = compileGlsl(ShaderStage::Compute, assemble(def.value()).source);
    ASSERT_FALSE(r.ok()) << bad;
    EXPECT_EQ(firstError(r.error()).line, 2) << bad;
  }
}

TEST(TermIncludes, ErrorsAfterAnIncludeKeepTheUsersLine) {
  // Line 7 names an undeclared identifier; the term's text before it must not shift the line.
  Result<SpirvBinary> r =
      compileText(fileWithInclude("#include \"terms/d_ggx.glsl\"", "return vec3(D_GGX(0.9, a) * nope);"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(firstError(r.error()).line, 7) << firstError(r.error()).message;
  EXPECT_NE(firstError(r.error()).message.find("nope"), std::string::npos);

  // The same in a sample section after includes in both sections.
  const std::string text =
      "::begin shader\n"                     // 1
      "#include \"terms/f_schlick.glsl\"\n"  // 2
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return F_Schlick(0.5, vec3(0.04)); }\n"
      "::end shader\n"                       // 4
      "::begin sample\n"                     // 5
      "#include \"terms/g_vcavity.glsl\"\n"  // 6
      "#include \"terms/d_ggx.glsl\"\n"      // 7
      "vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, out float pdf) {\n"
      "  L = N; pdf = G_VCavity(1.0, 1.0, 1.0, 1.0);\n"  // 9
      "  return BRDF(L, V, N, X, Y) * missing;\n"        // 10
      "}\n"
      "::end sample\n";
  Result<SpirvBinary> s = compileText(text);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(firstError(s.error()).line, 10) << firstError(s.error()).message;
}

TEST(TermIncludes, RedefiningAnIncludedTermIsAnErrorOnTheUsersLine) {
  Result<SpirvBinary> r = compileText(fileWithInclude(
      "#include \"terms/d_ggx.glsl\"\nfloat D_GGX(float NoH, float a) { return 1.0; }", "return vec3(D_GGX(0.9, a));"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(firstError(r.error()).line, 6) << firstError(r.error()).message;
}

class TermIncludesOnDevice : public DeviceTest {};

// A user BRDF as PUT /api/brdfs compiles it: the renderer resolves includes from its own
// shader folder, and a bad include is a CompileError (422) on the include's line.
TEST_F(TermIncludesOnDevice, UserBrdfsIncludeTermsThroughTheRenderer) {
  auto good = inlineBrdf(fileWithInclude("#include \"terms/d_ggx.glsl\""));
  ASSERT_TRUE(good);
  auto compiled = renderer_->compileBrdf(*good);
  EXPECT_TRUE(compiled.ok()) << (compiled.ok() ? "" : compiled.error().message);

  auto unknown = inlineBrdf(fileWithInclude("#include \"terms/g_vgroove.glsl\""));
  ASSERT_TRUE(unknown);
  auto failed = renderer_->compileBrdf(*unknown);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.error().code, ErrorCode::CompileError);
  EXPECT_EQ(firstError(failed.error()).line, 5) << firstError(failed.error()).message;

  Result<BrdfDefinition> escaping = parseBrdf(fileWithInclude("#include \"../kernels/shade.comp.glsl\""));
  ASSERT_FALSE(escaping.ok());
  EXPECT_EQ(escaping.error().code, ErrorCode::CompileError);
  EXPECT_EQ(firstError(escaping.error()).line, 5);
}

TEST_F(TermIncludesOnDevice, EveryBuiltinCompiles) {
  namespace fs = std::filesystem;
  int count = 0;
  for (const auto& e : fs::directory_iterator(kShaderDir + "/brdfs")) {
    if (e.path().extension() != ".brdf") continue;
    SCOPED_TRACE(e.path().filename().string());
    auto def = builtin(e.path().stem().string());
    ASSERT_TRUE(def);
    auto compiled = renderer_->compileBrdf(*def);
    EXPECT_TRUE(compiled.ok()) << (compiled.ok() ? "" : compiled.error().message);
    ++count;
  }
  EXPECT_GT(count, 20);
}

}  // namespace
}  // namespace brdfa
