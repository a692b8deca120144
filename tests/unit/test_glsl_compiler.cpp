// glslang in process, and diagnostics mapped back to lines of the submitted .brdf file.
#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <gtest/gtest.h>

#include <atomic>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "brdfa/brdf.h"

#include "programs/glsl_compiler.h"
#include "programs/program_assembler.h"

namespace brdfa {
namespace {

constexpr uint32_t kSpirvMagic = 0x07230203;

const char* kIntegrator =
    "layout(local_size_x = 1) in;\n"
    "layout(std430, set = 0, binding = 0) buffer O { vec4 o; };\n"
    "void main() {\n"
    "  o = vec4(BRDF(vec3(0,0,1), vec3(0,0,1), vec3(0,0,1), vec3(1,0,0), vec3(0,1,0)), 1);\n"
    "}\n";

// A .brdf file with known line numbers; lines 9, 12 and 19 can be replaced by a broken line.
std::string brdfFile(const std::string& line9 = "float unused = 1.0;", const std::string& line12 = "float k = 1.0;",
                     const std::string& line19 = "pdf *= 1.0;") {
  return "analytic\n"                      // 1
         "::begin parameters\n"            // 2
         "float roughness 0 1 0.5\n"       // 3
         "color Kd 0.8 0.8 0.8\n"          // 4
         "bool useK 1\n"                   // 5
         "::end parameters\n"              // 6
         "::begin shader\n"                // 7
         "const float PI = 3.14159265;\n"  // 8
         + line9 +
         "\n"                                                            // 9
         "float helper(float x) { return useK ? x * roughness : x; }\n"  // 10
         "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n"         // 11
         "  " +
         line12 +
         "\n"                                           // 12
         "  return Kd / PI * helper(dot(N, L)) * k;\n"  // 13
         "}\n"                                          // 14
         "::end shader\n"                               // 15
         "::begin sample\n"                             // 16
         "vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, out float pdf) {\n"
         "  L = N; pdf = 1.0;\n"  // 18
         "  " +
         line19 +
         "\n"                               // 19
         "  return BRDF(L, V, N, X, Y);\n"  // 20
         "}\n"                              // 21
         "::end sample\n";                  // 22
}

// `chunks` go before the BRDF's text (as its inputs do).
Result<SpirvBinary> compileBrdf(const std::string& text, const std::string& integrator = kIntegrator,
                                std::vector<std::string> chunks = {}) {
  Result<BrdfDefinition> def = parseBrdf(text);
  if (!def.ok()) return def.takeError();
  ProgramSpec spec;
  spec.brdf = &def.value();
  spec.integrator = integrator;
  spec.userChunks = std::move(chunks);
  return compileGlsl(ShaderStage::Compute, assembleProgram(spec).source);
}

const Diagnostic& firstDiagnostic(const Result<SpirvBinary>& r) {
  static const Diagnostic none{-1, 0, "none", "no diagnostics"};
  if (r.ok() || r.error().diagnostics.empty()) return none;
  return r.error().diagnostics.front();
}

TEST(GlslCompiler, ValidBrdfCompilesToSpirv) {
  Result<SpirvBinary> r = compileBrdf(brdfFile());
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_FALSE(r->words.empty());
  EXPECT_EQ(r->words[0], kSpirvMagic);
  EXPECT_GT(r->compileMs, 0.0);
  EXPECT_TRUE(r->warnings.empty());
}

TEST(GlslCompiler, LambertWithoutParametersCompiles) {
  Result<SpirvBinary> r = compileBrdf(
      "analytic\n::begin shader\n"
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1.0 / 3.14159265); }\n"
      "::end shader\n");
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_GT(r->words.size(), 5u);
  EXPECT_EQ(r->words[0], kSpirvMagic);
}

// Documents glslang's #line semantics for `#version 450` (GLSL >= 3.30): the line after
// `#line N S` is line N, not N + 1. The assembler relies on this.
TEST(GlslCompiler, LineDirectiveNamesTheNextLine) {
  const std::string src =
      "#version 450\n"
      "layout(local_size_x = 1) in;\n"
      "#line 40 1\n"
      "float f() { return missingName; }\n"
      "void main() {}\n";
  Result<SpirvBinary> r = compileGlsl(ShaderStage::Compute, src);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::CompileError);
  EXPECT_EQ(firstDiagnostic(r).line, 40);
  EXPECT_NE(firstDiagnostic(r).message.find("missingName"), std::string::npos);
  EXPECT_NE(r.error().message.find("line 40"), std::string::npos) << r.error().message;
}

TEST(GlslCompiler, SyntaxErrorMapsToFileLine) {
  Result<SpirvBinary> r = compileBrdf(brdfFile("float broken = 1.0 +;"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::CompileError);
  EXPECT_EQ(firstDiagnostic(r).line, 9) << firstDiagnostic(r).message;
  EXPECT_EQ(firstDiagnostic(r).severity, "error");
  EXPECT_NE(firstDiagnostic(r).message.find("syntax error"), std::string::npos);
  // The summary line "N compilation errors. No code generated." is not a diagnostic.
  for (const Diagnostic& d : r.error().diagnostics)
    EXPECT_EQ(d.message.find("compilation errors"), std::string::npos) << d.message;
}

TEST(GlslCompiler, UndeclaredIdentifierMapsToFileLine) {
  Result<SpirvBinary> r = compileBrdf(brdfFile("float unused = 1.0;", "float k = notDeclared;"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(firstDiagnostic(r).line, 12) << firstDiagnostic(r).message;
  EXPECT_NE(firstDiagnostic(r).message.find("notDeclared"), std::string::npos);
  EXPECT_NE(firstDiagnostic(r).message.find("undeclared identifier"), std::string::npos);
}

TEST(GlslCompiler, ErrorInSampleSectionMapsToFileLine) {
  Result<SpirvBinary> r = compileBrdf(brdfFile("float unused = 1.0;", "float k = 1.0;", "pdf = undeclaredPdf;"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(firstDiagnostic(r).line, 19) << firstDiagnostic(r).message;
  EXPECT_NE(firstDiagnostic(r).message.find("undeclaredPdf"), std::string::npos);
}

TEST(GlslCompiler, ErrorInGeneratedCodeHasLineZero) {
  const std::string integrator =
      "layout(local_size_x = 1) in;\n"
      "void main() { float x = notInTheIntegrator; }\n";
  Result<SpirvBinary> r = compileBrdf(brdfFile(), integrator);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(firstDiagnostic(r).line, 0);
  EXPECT_EQ(firstDiagnostic(r).message.rfind("in generated code: ", 0), 0u) << firstDiagnostic(r).message;
  EXPECT_NE(firstDiagnostic(r).message.find("notInTheIntegrator"), std::string::npos);
}

TEST(GlslCompiler, UserDiagnosticsComeFirst) {
  // The generated chunk's warning is reported by glslang before the user's error.
  Result<SpirvBinary> r =
      compileBrdf(brdfFile("float broken = 1.0 +;"), kIntegrator, {"#extension GL_EXT_no_such_extension : warn\n"});
  ASSERT_FALSE(r.ok());
  ASSERT_GE(r.error().diagnostics.size(), 2u);
  EXPECT_EQ(r.error().diagnostics[0].line, 9);
  const Diagnostic& last = r.error().diagnostics.back();
  EXPECT_EQ(last.line, 0);
  EXPECT_EQ(last.severity, "warning");
  EXPECT_NE(last.message.find("GL_EXT_no_such_extension"), std::string::npos) << last.message;
}

TEST(GlslCompiler, WarningsOfASuccessfulCompile) {
  const std::string src =
      "#version 450\n"
      "#line 1 0\n"
      "#extension GL_EXT_no_such_extension : warn\n"
      "layout(local_size_x = 1) in;\n"
      "void main() {}\n";
  Result<SpirvBinary> r = compileGlsl(ShaderStage::Compute, src);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->warnings.size(), 1u);
  EXPECT_EQ(r->warnings[0].severity, "warning");
  EXPECT_EQ(r->warnings[0].line, 0);
  EXPECT_EQ(r->warnings[0].message.rfind("in generated code: line 1: ", 0), 0u) << r->warnings[0].message;
}

TEST(GlslCompiler, LinkErrorIsReported) {
  Result<SpirvBinary> r = compileGlsl(ShaderStage::Compute, "#version 450\nlayout(local_size_x = 1) in;\n");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::CompileError);
  ASSERT_FALSE(r.error().diagnostics.empty());
  EXPECT_EQ(firstDiagnostic(r).line, 0);
}

TEST(GlslCompiler, OtherStages) {
  Result<SpirvBinary> vs = compileGlsl(ShaderStage::Vertex, "#version 450\nvoid main() { gl_Position = vec4(0); }\n");
  ASSERT_TRUE(vs.ok()) << vs.error().message;
  EXPECT_EQ(vs->words[0], kSpirvMagic);
  Result<SpirvBinary> fs = compileGlsl(
      ShaderStage::Fragment, "#version 450\nlayout(location = 0) out vec4 c;\nvoid main() { c = vec4(1); }\n");
  ASSERT_TRUE(fs.ok()) << fs.error().message;
  EXPECT_EQ(fs->words[0], kSpirvMagic);
}

TEST(GlslCompiler, ConcurrentCompilesAreSafe) {
  const std::string good = brdfFile();
  const std::string bad = brdfFile("float unused = 1.0;", "float k = notDeclared;");
  std::atomic<int> failures{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 5; ++i) {
        const bool wantOk = (t + i) % 2 == 0;
        Result<SpirvBinary> r = compileBrdf(wantOk ? good : bad);
        if (r.ok() != wantOk) ++failures;
        if (!wantOk && !r.ok() && firstDiagnostic(r).line != 12) ++failures;
      }
    });
  }
  for (std::thread& th : threads) th.join();
  EXPECT_EQ(failures.load(), 0);
}

// layoutParams() hand-codes std140; glslang's reflection is an independent judge of it.
TEST(GlslCompiler, ParamLayoutAgreesWithGlslangReflection) {
  BrdfDefinition brdf;
  const std::vector<std::pair<std::string, ParamType>> members = {
      {"a", ParamType::Float}, {"b", ParamType::Color}, {"c", ParamType::Bool},
      {"d", ParamType::Float}, {"e", ParamType::Color}, {"f", ParamType::Color},
      {"g", ParamType::Bool},  {"h", ParamType::Bool},  {"i", ParamType::Color}};
  for (const auto& [name, type] : members) {
    BrdfParam p;
    p.name = name;
    p.type = type;
    brdf.params.push_back(p);
  }
  brdf.shader = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(a); }\n";
  brdf.shaderFirstLine = 1;
  ProgramSpec spec;
  spec.brdf = &brdf;
  spec.integrator = kIntegrator;
  AssembledProgram program = assembleProgram(spec);
  ASSERT_TRUE(compileGlsl(ShaderStage::Compute, program.source).ok());  // also initialises glslang

  glslang::TShader shader(EShLangCompute);
  const char* text = program.source.c_str();
  shader.setStrings(&text, 1);
  shader.setEnvInput(glslang::EShSourceGlsl, EShLangCompute, glslang::EShClientVulkan, 100);
  shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_0);
  shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_0);
  const auto messages = static_cast<EShMessages>(EShMsgSpvRules | EShMsgVulkanRules);
  ASSERT_TRUE(shader.parse(GetDefaultResources(), 450, false, messages)) << shader.getInfoLog();
  glslang::TProgram linked;
  linked.addShader(&shader);
  ASSERT_TRUE(linked.link(messages)) << linked.getInfoLog();
  ASSERT_TRUE(linked.buildReflection(EShReflectionAllBlockVariables));

  std::map<std::string, int> reflected;
  for (int i = 0; i < linked.getNumUniformVariables(); ++i)
    reflected[linked.getUniform(i).name] = linked.getUniform(i).offset;
  for (const ParamBlockLayout::Entry& e : program.params.entries) {
    ASSERT_TRUE(reflected.count(e.name)) << e.name;
    EXPECT_EQ(reflected[e.name], static_cast<int>(e.offset)) << e.name;
  }
  int blockSize = -1;
  for (int i = 0; i < linked.getNumUniformBlocks(); ++i)
    if (linked.getUniformBlock(i).name == "BrdfParams") blockSize = linked.getUniformBlock(i).size;
  // glslang reports the unpadded size; ours is rounded up to 16.
  ASSERT_GT(blockSize, 0);
  EXPECT_EQ(program.params.size, (static_cast<uint32_t>(blockSize) + 15u) / 16u * 16u);
}

TEST(GlslCompiler, VersionIsStableAndNamesGlslang) {
  const std::string v = compilerVersion();
  EXPECT_NE(v.find("glslang"), std::string::npos) << v;
  EXPECT_EQ(v, compilerVersion());
}

}  // namespace
}  // namespace brdfa
