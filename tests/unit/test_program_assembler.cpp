// Program assembly: std140 parameter block, packing, section order, #line directives, the
// renaming of user functions that shadow GLSL built-ins, and the BRDFA Engine's PI and LI.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "programs/brdf_features.h"
#include "programs/glsl_compiler.h"
#include "programs/program_assembler.h"

namespace brdfa {
namespace {

BrdfParam makeParam(const std::string& name, ParamType type, Vec3 def = {0, 0, 0}) {
  BrdfParam p;
  p.name = name;
  p.type = type;
  p.defaultValue = def;
  return p;
}

float floatAt(const std::vector<uint8_t>& bytes, uint32_t offset) {
  float v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

uint32_t uintAt(const std::vector<uint8_t>& bytes, uint32_t offset) {
  uint32_t v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

std::vector<std::string> linesOf(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

TEST(ParamLayout, Std140OffsetsForMixedTypes) {
  // std140: a=0 (4 bytes); b is a vec3, 16-aligned -> 16..28; c (bool as uint) packs into the
  // vec3's tail at 28; d at 32; end 36 rounds up to 48.
  ParamBlockLayout l = layoutParams({makeParam("a", ParamType::Float), makeParam("b", ParamType::Color),
                                     makeParam("c", ParamType::Bool), makeParam("d", ParamType::Float)});
  ASSERT_EQ(l.entries.size(), 4u);
  EXPECT_EQ(l.entries[0].offset, 0u);
  EXPECT_EQ(l.entries[1].offset, 16u);
  EXPECT_EQ(l.entries[2].offset, 28u);
  EXPECT_EQ(l.entries[3].offset, 32u);
  EXPECT_EQ(l.size, 48u);
  EXPECT_EQ(l.entries[2].name, "c");
  EXPECT_EQ(l.entries[2].type, ParamType::Bool);
}

TEST(ParamLayout, OtherShapes) {
  EXPECT_EQ(layoutParams({}).size, 16u);
  EXPECT_TRUE(layoutParams({}).entries.empty());
  EXPECT_EQ(layoutParams({makeParam("a", ParamType::Float)}).size, 16u);

  ParamBlockLayout two = layoutParams({makeParam("a", ParamType::Color), makeParam("b", ParamType::Color)});
  EXPECT_EQ(two.entries[1].offset, 16u);
  EXPECT_EQ(two.size, 32u);

  std::vector<BrdfParam> five;
  for (const char* n : {"a", "b", "c", "d", "e"}) five.push_back(makeParam(n, ParamType::Float));
  ParamBlockLayout f = layoutParams(five);
  EXPECT_EQ(f.entries[4].offset, 16u);
  EXPECT_EQ(f.size, 32u);

  // float then color: the color must skip to 16, not sit at 4.
  ParamBlockLayout fc = layoutParams({makeParam("a", ParamType::Float), makeParam("b", ParamType::Color)});
  EXPECT_EQ(fc.entries[1].offset, 16u);
  EXPECT_EQ(fc.size, 32u);
}

TEST(ParamLayout, GlslDeclaration) {
  ParamBlockLayout l = layoutParams(
      {makeParam("roughness", ParamType::Float), makeParam("Kd", ParamType::Color), makeParam("iso", ParamType::Bool)});
  EXPECT_EQ(l.glsl(),
            "layout(std140, set = 1, binding = 0) uniform BrdfParams {\n"
            "  float roughness;\n"
            "  vec3 Kd;\n"
            "  bool iso;\n"
            "};\n");
  EXPECT_EQ(layoutParams({}).glsl(),
            "layout(std140, set = 1, binding = 0) uniform BrdfParams {\n"
            "  float brdfa_pad_;\n"
            "};\n");
}

TEST(ParamLayout, PackWritesDefaultsAndGivenValues) {
  BrdfDefinition brdf;
  brdf.params = {makeParam("a", ParamType::Float, {0.25f, 0, 0}), makeParam("b", ParamType::Color, {0.1f, 0.2f, 0.3f}),
                 makeParam("c", ParamType::Bool, {1, 0, 0}), makeParam("d", ParamType::Float, {0.75f, 0, 0})};
  ParamBlockLayout l = layoutParams(brdf.params);

  std::vector<uint8_t> defaults = l.pack(brdf, {});
  ASSERT_EQ(defaults.size(), 48u);
  EXPECT_FLOAT_EQ(floatAt(defaults, 0), 0.25f);
  EXPECT_FLOAT_EQ(floatAt(defaults, 16), 0.1f);
  EXPECT_FLOAT_EQ(floatAt(defaults, 20), 0.2f);
  EXPECT_FLOAT_EQ(floatAt(defaults, 24), 0.3f);
  EXPECT_EQ(uintAt(defaults, 28), 1u);
  EXPECT_FLOAT_EQ(floatAt(defaults, 32), 0.75f);
  for (uint32_t o : {4u, 8u, 12u, 36u, 40u, 44u}) EXPECT_EQ(uintAt(defaults, o), 0u) << o;

  std::vector<uint8_t> given = l.pack(brdf, {{"b", {0.9f, 0.8f, 0.7f}},
                                             {"c", {0, 0, 0}},
                                             {"d", {5.0f, 0, 0}},  // not clamped here
                                             {"unknown", {1, 1, 1}}});
  EXPECT_FLOAT_EQ(floatAt(given, 0), 0.25f);  // default kept
  EXPECT_FLOAT_EQ(floatAt(given, 16), 0.9f);
  EXPECT_FLOAT_EQ(floatAt(given, 20), 0.8f);
  EXPECT_FLOAT_EQ(floatAt(given, 24), 0.7f);
  EXPECT_EQ(uintAt(given, 28), 0u);
  EXPECT_FLOAT_EQ(floatAt(given, 32), 5.0f);
}

TEST(ParamLayout, PackEmptyBlock) {
  BrdfDefinition brdf;
  std::vector<uint8_t> bytes = layoutParams({}).pack(brdf, {});
  EXPECT_EQ(bytes, std::vector<uint8_t>(16, 0));
}

TEST(Fnv1a64, KnownVectors) {
  EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ull);
  EXPECT_NE(fnv1a64("foobar", 1), fnv1a64("foobar"));
}

class Assembly : public ::testing::Test {
 protected:
  void SetUp() override {
    brdf.params = {makeParam("roughness", ParamType::Float, {0.5f, 0, 0})};
    brdf.shader =
        "float f() { return roughness; }\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, "
        "vec3 Y) { return vec3(f()); }";  // no trailing newline on purpose
    brdf.shaderFirstLine = 7;
    spec.brdf = &brdf;
    spec.defines = {"BRDFA_ONE", "BRDFA_TWO 2"};
    spec.userChunks = {"// user chunk\nvec2 texCoord;"};
    spec.commonChunks = {"// chunk A\nfloat chunkA() { return 1.0; }", "// chunk B\n"};
    spec.integrator = "// integrator\nvoid main() {}\n";
  }
  BrdfDefinition brdf;
  ProgramSpec spec;
};

TEST_F(Assembly, FixedOrderAndLineDirectives) {
  AssembledProgram p = assembleProgram(spec);
  const std::vector<std::string> lines = linesOf(p.source);
  ASSERT_GE(lines.size(), 10u);
  EXPECT_EQ(lines[0], "#version 450");
  EXPECT_EQ(lines[1], "#define BRDFA_ONE");
  EXPECT_EQ(lines[2], "#define BRDFA_TWO 2");
  EXPECT_EQ(lines[3], "layout(std140, set = 1, binding = 0) uniform BrdfParams {");
  EXPECT_EQ(p.source.find("GL_GOOGLE_include_directive"), std::string::npos);

  // The BRDF's inputs, the BRDF's text, then the integrator's common code (which the BRDF's
  // text therefore cannot name), then the integrator.
  const size_t block = p.source.find("uniform BrdfParams");
  const size_t userChunk = p.source.find("// user chunk");
  const size_t chunkA = p.source.find("// chunk A");
  const size_t chunkB = p.source.find("// chunk B");
  const size_t userLine = p.source.find("#line 7 1\nfloat f()");
  const size_t integrator = p.source.find("// integrator");
  ASSERT_NE(userLine, std::string::npos) << p.source;
  EXPECT_LT(block, userChunk);
  EXPECT_LT(userChunk, userLine);
  EXPECT_LT(userLine, chunkA);
  EXPECT_LT(chunkA, chunkB);
  EXPECT_LT(chunkB, integrator);
  // The chunk without a trailing newline must not run into the next one.
  EXPECT_NE(p.source.find("return 1.0; }\n// chunk B"), std::string::npos);

  // `#line k 0` after the user's text names the true line of the line after it.
  for (size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].rfind("#line ", 0) == 0 && lines[i].size() > 2 && lines[i].substr(lines[i].size() - 2) == " 0") {
      const int k = std::stoi(lines[i].substr(6));
      EXPECT_EQ(k, static_cast<int>(i) + 2) << "directive on line " << i + 1;
      ASSERT_LT(i + 1, lines.size());
      EXPECT_EQ(lines[i + 1], "// chunk A");
    }
  }
  EXPECT_EQ(p.hash, fnv1a64(p.source));
  EXPECT_EQ(p.params.size, 16u);
}

TEST_F(Assembly, MacrosOfTheBrdfEndWithItsText) {
  // A BRDF's macros must not rewrite the integrator's code after it.
  brdf.shader =
      "#define brdfa_accum evil\n  #  define  TWO 2.0\n#if 0\n#define HIDDEN 1\n#endif\n"
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(TWO); }\n";
  AssembledProgram p = assembleProgram(spec);
  const size_t lastUser = p.source.find("vec3 BRDF(");
  const size_t chunkA = p.source.find("// chunk A");
  for (const char* name : {"brdfa_accum", "TWO", "HIDDEN"}) {
    const size_t undef = p.source.find(std::string("#undef ") + name + "\n");
    ASSERT_NE(undef, std::string::npos) << name << "\n" << p.source;
    EXPECT_LT(lastUser, undef) << name;
    EXPECT_LT(undef, chunkA) << name;
  }
}

TEST_F(Assembly, SampleSectionGetsItsOwnLine) {
  brdf.sampleShader =
      "vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, "
      "out float pdf) { L = N; pdf = 1.0; return vec3(1); }\n";
  brdf.sampleFirstLine = 20;
  AssembledProgram p = assembleProgram(spec);
  const size_t user = p.source.find("#line 7 1\n");
  const size_t sample = p.source.find("#line 20 1\nvec3 sampleBRDF");
  const size_t generated = p.source.find(" 0\n// integrator");
  ASSERT_NE(sample, std::string::npos) << p.source;
  EXPECT_LT(user, sample);
  EXPECT_LT(sample, generated);
}

TEST_F(Assembly, HashChangesWithSource) {
  const uint64_t h1 = assembleProgram(spec).hash;
  brdf.shader += "\n// edit";
  EXPECT_NE(assembleProgram(spec).hash, h1);
  EXPECT_EQ(assembleProgram(spec).hash, assembleProgram(spec).hash);
}

// Old desktop GLSL (what the Explorer compiled its files as) let a user function hide a
// built-in of the same name; glslang under #version 450 rejects the redefinition. The assembler
// renames such functions with a macro that covers only the user's sections.
TEST_F(Assembly, UserFunctionsNamedLikeBuiltinsAreRenamedForUserTextOnly) {
  brdf.shader =
      "// a comment mentioning float mix(float a) is not a declaration\n"
      "vec3 reflect(vec3 d, vec3 n) { return 2.0 * dot(d, n) * n - d; }\n"
      "float step (float e, float x);\n"
      "float step (float e, float x) { return x < e ? 0.0 : 1.0; }\n"
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n"
      "  float t = max(0.0, dot(reflect(L, N), V));\n"  // calls are not declarations
      "  return vec3(step(0.5, t) * roughness);\n"
      "}\n";
  brdf.sampleShader =
      "vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, "
      "out float pdf) { L = reflect(V, N); pdf = 1.0; return BRDF(L, V, N, X, Y); }\n";
  brdf.sampleFirstLine = 30;
  AssembledProgram p = assembleProgram(spec);
  const std::string& src = p.source;

  const size_t defReflect = src.find("#define reflect brdfa_user_reflect\n");
  const size_t defStep = src.find("#define step brdfa_user_step\n");
  const size_t user = src.find("#line 7 1\n// a comment");
  const size_t sample = src.find("#line 30 1\nvec3 sampleBRDF");
  const size_t undefReflect = src.find("#undef reflect\n");
  const size_t undefStep = src.find("#undef step\n");
  const size_t integrator = src.find("// integrator");
  ASSERT_NE(defReflect, std::string::npos) << src;
  ASSERT_NE(defStep, std::string::npos) << src;
  ASSERT_NE(user, std::string::npos) << src;
  ASSERT_NE(sample, std::string::npos) << src;
  ASSERT_NE(undefReflect, std::string::npos) << src;
  ASSERT_NE(undefStep, std::string::npos) << src;
  // After the BRDF's inputs, before the first user line; undone after the last user section,
  // before the integrator's common code.
  EXPECT_LT(src.find("// user chunk"), defReflect);
  EXPECT_LT(undefReflect, src.find("// chunk A"));
  EXPECT_LT(defReflect, user);
  EXPECT_LT(defStep, user);
  EXPECT_LT(sample, undefReflect);
  EXPECT_LT(undefStep, integrator);
  EXPECT_EQ(src.find("#define mix"), std::string::npos) << "names in comments are ignored";
  EXPECT_EQ(src.find("#define max"), std::string::npos) << "calls are not declarations";
  EXPECT_EQ(src.find("#define dot"), std::string::npos);
  // The user's text is emitted unchanged.
  EXPECT_NE(src.find(brdf.shader), std::string::npos);

  // The generated `#line k 0` still names its true line.
  const std::vector<std::string> lines = linesOf(src);
  bool sawGenerated = false;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].rfind("#line ", 0) == 0 && lines[i].substr(lines[i].size() - 2) == " 0") {
      EXPECT_EQ(std::stoi(lines[i].substr(6)), static_cast<int>(i) + 2);
      sawGenerated = true;
    }
  }
  EXPECT_TRUE(sawGenerated);
}

TEST_F(Assembly, NoRenamingWithoutBuiltinNamedDeclarations) {
  brdf.shader =
      "float reflectance(float x) { return x; }\n"  // a prefix of a built-in name
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n"
      "  return reflect(-L, N) * reflectance(roughness);\n"
      "}\n";
  const std::string src = assembleProgram(spec).source;
  EXPECT_EQ(src.find("#define reflect"), std::string::npos) << src;
  EXPECT_EQ(src.find("#undef"), std::string::npos) << src;
}

// A synthetic file in the old-GLSL style: it overrides `reflect` with the mirror-about-N
// convention and `smoothstep` with a hard step. It compiles, the built-ins stay available to
// the generated code on both sides of the user text, and diagnostics keep their file lines.
constexpr const char* kOverrideIntegrator =
    "layout(local_size_x = 1) in;\n"
    "layout(std430, set = 0, binding = 0) buffer O { vec4 o; };\n"
    "void main() {\n"
    "  vec3 n = vec3(0, 0, 1);\n"
    "  vec3 r = reflect(vec3(0.6, 0, -0.8), n);\n"  // the built-in, vec3 version
    "  o = vec4(BRDF(vec3(0.6, 0, 0.8), vec3(-0.6, 0, 0.8), n, vec3(1, 0, 0), vec3(0, 1, 0)),\n"
    "           smoothstep(0.0, 1.0, r.z));\n"
    "}\n";

std::string overridingShader(const std::string& line5) {
  return "vec3 reflect(vec3 d, vec3 n)\n"         // 10
         "{ return 2.0 * dot(d, n) * n - d; }\n"  // 11
         "float smoothstep(float lo, float hi, float x) { return x < lo ? 0.0 : 1.0; }\n"
         "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n"  // 13
         "  " +
         line5 +
         "\n"  // 14
         "  return vec3(smoothstep(0.9, 1.0, dot(reflect(L, N), V)) * roughness);\n"
         "}\n";
}

TEST_F(Assembly, BuiltinOverridesCompileAndKeepLineNumbers) {
  spec.integrator = kOverrideIntegrator;
  spec.commonChunks = {"float chunkUsesBuiltin(vec3 v) { return reflect(v, vec3(0, 0, 1)).z; }"};
  brdf.shaderFirstLine = 10;
  brdf.shader = overridingShader("float unused = 1.0;");
  Result<SpirvBinary> ok = compileGlsl(ShaderStage::Compute, assembleProgram(spec).source);
  EXPECT_TRUE(ok.ok()) << (ok.ok() ? "" : ok.error().message) << "\n" << assembleProgram(spec).source;

  brdf.shader = overridingShader("float broken = ;");
  Result<SpirvBinary> bad = compileGlsl(ShaderStage::Compute, assembleProgram(spec).source);
  ASSERT_FALSE(bad.ok());
  ASSERT_FALSE(bad.error().diagnostics.empty());
  EXPECT_EQ(bad.error().diagnostics.front().line, 14) << bad.error().diagnostics.front().message;
}

// What gives a name a meaning of its own in a file (brdf_features.h), for the BRDFA Engine's
// PI and LI below.
TEST(DeclaresName, DefinitionsAndDeclarationsButNotUses) {
  const struct {
    const char* code;
    bool declares;
  } cases[] = {
      {"#define PI 3.14159265359\n", true},
      {"  #  define PI 3.0\n", true},
      {"#undef PI\n", true},
      {"const float PI = 3.14159;\n", true},
      {"float PI;\n", true},
      {"float f(float PI) { return PI; }\n", true},
      {"float PI() { return 3.0; }\n", true},
      {"struct S { float PI; };\n", true},
      {"float[2] PI = float[2](1.0, 2.0);\n", true},
      {"void f() { PI = 3.0; }\n", true},
      {"vec3 f() { return vec3(PI); }\n", false},
      {"vec3 f() { return vec3(2.0 * PI, PI / 2.0, float(PI == 3.0)); }\n", false},
      {"float f() { return PI; }\n", false},
      {"#define TWO_PI (2.0 * PI)\n#if defined(PI)\n#endif\n", false},
      {"// const float PI = 3.0;\n/* #define PI 3.0 */ float f() { return PI; }\n", false},
      {"const float PIE = 3.0; float API = PIE;\n", false},
  };
  for (const auto& c : cases) EXPECT_EQ(declaresName(c.code, "PI"), c.declares) << c.code;
}

// A minimal program around a BRDFA Engine render() file.
constexpr const char* kRenderIntegrator =
    "layout(local_size_x = 1) in;\n"
    "layout(std430, set = 0, binding = 0) buffer O { vec4 o; };\n"
    "void main() {\n"
    "  o = vec4(render(vec3(0, 0, 1), vec3(0, 0, 1), vec3(0, 0, 1), vec2(0.0), mat3(1.0)), 1.0);\n"
    "}\n";

std::string renderFile(const std::string& before, const std::string& body) {
  return before + "vec3 render(vec3 L, vec3 N, vec3 V, vec2 textureCord, mat3 worldToLocal) {\n  " + body + "\n}\n";
}

// The engine's host shader defined PI and LI before the file's text (program_assembler.cpp):
// a legacy file sees them, for its text only.
TEST_F(Assembly, LegacyFileSeesTheEnginesPiAndLi) {
  brdf.format = BrdfFormat::Legacy;
  brdf.params.clear();
  brdf.shader = renderFile("", "return vec3(LI * dot(N, L) / PI);");
  const std::string src = assembleProgram(spec).source;
  auto at = [&](const char* text) {
    const size_t i = src.find(text);
    EXPECT_NE(i, std::string::npos) << text << " in\n" << src;
    return i;
  };
  // In the generated region after the file's inputs, so its line numbers are untouched; gone
  // before the integrator's code.
  const size_t user = at("#line 7 1\nvec3 render(");
  for (const char* define : {"#define PI 3.14159265359\n", "#define LI 8.\n"}) {
    EXPECT_LT(at("// user chunk"), at(define)) << define;
    EXPECT_LT(at(define), user) << define;
  }
  for (const char* undef : {"#undef PI\n", "#undef LI\n"}) {
    EXPECT_LT(user, at(undef)) << undef;
    EXPECT_LT(at(undef), at("// chunk A")) << undef;
  }

  spec.integrator = kRenderIntegrator;
  Result<SpirvBinary> r = compileGlsl(ShaderStage::Compute, assembleProgram(spec).source);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);

  // Files in the native format never see them.
  brdf.format = BrdfFormat::Explorer;
  brdf.shader = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1.0); }\n";
  const std::string native = assembleProgram(spec).source;
  EXPECT_EQ(native.find("#define PI"), std::string::npos) << native;
  EXPECT_EQ(native.find("#define LI"), std::string::npos) << native;
}

// The engine appended the file to its own `#define PI 3.14159265359`: an identical #define
// compiled there, a different one or a `const float PI` did not. Here all of them compile,
// with the file's own meaning where it gives one, and a file's error keeps its line.
TEST_F(Assembly, LegacyFilesWithTheirOwnPiOrLiCompile) {
  brdf.format = BrdfFormat::Legacy;
  brdf.params.clear();
  brdf.shaderFirstLine = 1;
  spec.integrator = kRenderIntegrator;
  const struct {
    const char* before;
    const char* body;
    bool enginePi, engineLi;  // whether the engine's definitions are emitted
  } cases[] = {
      {"", "return vec3(PI, LI, 0.0);", true, true},
      {"#define PI 3.14159265359\n", "return vec3(PI, LI, 0.0);", false, true},
      {"#define PI 3.0\n", "return vec3(PI, LI, 0.0);", false, true},
      {"  # define PI (3.0)\n#define LI 2.0\n", "return vec3(PI, LI, 0.0);", false, false},
      {"const float PI = 3.0;\n", "return vec3(PI, LI, 0.0);", false, true},
      {"#undef PI\nconst float PI = 3.0;\n", "return vec3(PI);", false, true},
      {"const vec3 LI = vec3(2.0);\n", "return LI * PI;", true, false},
      {"", "float PI = 3.0; return vec3(PI);", false, true},
      {"", "return vec3(1.0);", true, true},  // unused: harmless
  };
  for (const auto& c : cases) {
    brdf.shader = renderFile(c.before, c.body);
    const std::string src = assembleProgram(spec).source;
    const size_t user = src.find("#line 1 1\n");  // the file's own text starts there
    ASSERT_NE(user, std::string::npos) << src;
    EXPECT_EQ(src.find("#define PI 3.14159265359\n") < user, c.enginePi) << src;
    EXPECT_EQ(src.find("#define LI 8.\n") < user, c.engineLi) << src;
    Result<SpirvBinary> r = compileGlsl(ShaderStage::Compute, src);
    EXPECT_TRUE(r.ok()) << c.before << c.body << ": " << (r.ok() ? "" : r.error().message);
  }

  // Only the file's own text counts against it: an error after the emitted lines names its line.
  brdf.shader = renderFile("const float PI = 3.0;\n", "return vec3(PI) + ;");
  Result<SpirvBinary> bad = compileGlsl(ShaderStage::Compute, assembleProgram(spec).source);
  ASSERT_FALSE(bad.ok());
  ASSERT_FALSE(bad.error().diagnostics.empty());
  EXPECT_EQ(bad.error().diagnostics.front().line, 3) << bad.error().diagnostics.front().message;
}

TEST(AssemblyNoBrdf, StillProducesAProgram) {
  ProgramSpec spec;
  spec.integrator = "void main() {}";
  AssembledProgram p = assembleProgram(spec);
  EXPECT_EQ(p.source.rfind("#version 450\n", 0), 0u);
  EXPECT_NE(p.source.find("brdfa_pad_"), std::string::npos);
  EXPECT_EQ(p.source.back(), '\n');
}

}  // namespace
}  // namespace brdfa
