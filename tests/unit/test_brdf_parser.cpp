// parseBrdf(): the .brdf contract of docs/design.md section 3.
#include <gtest/gtest.h>

#include <string>

#include "brdfa/brdf.h"

namespace brdfa {
namespace {

const char* kLambert =
    "analytic\n"                                                               // 1
    "# a comment line\n"                                                       // 2
    "::begin parameters\n"                                                     // 3
    "float roughness 0.001 1 0.3     # name min max\n"                         // 4
    "color Kd 0.8 0.7 .6            # rgb 0..1\n"                              // 5
    "bool  isotropic 1               # 0|1\n"                                  // 6
    "\n"                                                                       // 7
    "::end parameters\n"                                                       // 8
    "::begin shader\n"                                                         // 9
    "const float PI = 3.14159265358979323846;\n"                               // 10
    "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd / PI; }\n"  // 11
    "::end shader\n";                                                          // 12

// Builds a file whose parameter section holds `paramLine` on line 3.
std::string withParam(const std::string& paramLine) {
  return "analytic\n"
         "::begin parameters\n" +
         paramLine +
         "\n"
         "::end parameters\n"
         "::begin shader\n"
         "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1); }\n"
         "::end shader\n";
}

// Expects a CompileError whose first diagnostic is on `line` and mentions `fragment`.
void expectErrorAt(const std::string& text, int line, const std::string& fragment) {
  Result<BrdfDefinition> r = parseBrdf(text);
  ASSERT_FALSE(r.ok()) << text;
  EXPECT_EQ(r.error().code, ErrorCode::CompileError);
  ASSERT_FALSE(r.error().diagnostics.empty());
  const Diagnostic& d = r.error().diagnostics.front();
  EXPECT_EQ(d.line, line) << d.message;
  EXPECT_EQ(d.severity, "error");
  EXPECT_NE(d.message.find(fragment), std::string::npos) << d.message;
  EXPECT_NE(r.error().message.find(fragment), std::string::npos) << r.error().message;
}

TEST(BrdfParser, ParsesAllParameterTypes) {
  Result<BrdfDefinition> r = parseBrdf(kLambert);
  ASSERT_TRUE(r.ok()) << r.error().message;
  const BrdfDefinition& d = r.value();
  EXPECT_EQ(d.format, BrdfFormat::Explorer);
  ASSERT_EQ(d.params.size(), 3u);

  EXPECT_EQ(d.params[0].name, "roughness");
  EXPECT_EQ(d.params[0].type, ParamType::Float);
  EXPECT_FLOAT_EQ(d.params[0].min, 0.001f);
  EXPECT_FLOAT_EQ(d.params[0].max, 1.0f);
  EXPECT_FLOAT_EQ(d.params[0].defaultValue[0], 0.3f);
  EXPECT_EQ(d.params[0].line, 4);

  EXPECT_EQ(d.params[1].name, "Kd");
  EXPECT_EQ(d.params[1].type, ParamType::Color);
  EXPECT_FLOAT_EQ(d.params[1].defaultValue[0], 0.8f);
  EXPECT_FLOAT_EQ(d.params[1].defaultValue[1], 0.7f);
  EXPECT_FLOAT_EQ(d.params[1].defaultValue[2], 0.6f);
  EXPECT_EQ(d.params[1].line, 5);

  EXPECT_EQ(d.params[2].name, "isotropic");
  EXPECT_EQ(d.params[2].type, ParamType::Bool);
  EXPECT_FLOAT_EQ(d.params[2].defaultValue[0], 1.0f);
  EXPECT_EQ(d.params[2].line, 6);

  EXPECT_EQ(d.findParam("Kd"), &d.params[1]);
  EXPECT_EQ(d.findParam("kd"), nullptr);
  EXPECT_TRUE(d.warnings.empty());
  EXPECT_FALSE(d.hasSampler());
}

// What a file claims, in a comment line the Explorer's reader skips.
TEST(BrdfParser, ClaimsLine) {
  Result<BrdfDefinition> none = parseBrdf(kLambert);
  ASSERT_TRUE(none.ok());
  EXPECT_FALSE(none->claims.declared);
  EXPECT_FALSE(none->claims.reciprocity);

  Result<BrdfDefinition> r =
      parseBrdf(std::string("# claims: reciprocity,energy-conservation  non-negativity\n") + kLambert);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(r->claims.declared);
  EXPECT_EQ(r->claims.line, 1);
  EXPECT_TRUE(r->claims.reciprocity);
  EXPECT_TRUE(r->claims.energyConservation);
  EXPECT_TRUE(r->claims.nonNegativity);

  Result<BrdfDefinition> nothing = parseBrdf(std::string("# claims: none\n") + kLambert);
  ASSERT_TRUE(nothing.ok());
  EXPECT_TRUE(nothing->claims.declared);
  EXPECT_FALSE(nothing->claims.reciprocity || nothing->claims.energyConservation || nothing->claims.nonNegativity);

  expectErrorAt(std::string("analytic\n# claims: reciprocity, energy\n") + (kLambert + 9), 2, "unknown claim 'energy'");
  expectErrorAt(std::string("# claims: none\n# claims: reciprocity\n") + kLambert, 2, "second claims line");
}

TEST(BrdfParser, ShaderTextAndFirstLine) {
  Result<BrdfDefinition> r = parseBrdf(kLambert);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->shaderFirstLine, 10);
  EXPECT_EQ(r->shader,
            "const float PI = 3.14159265358979323846;\n"
            "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd / PI; }\n");
}

TEST(BrdfParser, CrlfAndMissingTrailingNewline) {
  std::string crlf;
  for (const char* p = kLambert; *p; ++p) {
    if (*p == '\n') crlf += '\r';
    crlf += *p;
  }
  crlf.resize(crlf.size() - 2);  // no newline after "::end shader"
  Result<BrdfDefinition> r = parseBrdf(crlf);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->params.size(), 3u);
  EXPECT_EQ(r->params[2].line, 6);
  EXPECT_FLOAT_EQ(r->params[2].defaultValue[0], 1.0f);
  EXPECT_EQ(r->shaderFirstLine, 10);
  EXPECT_EQ(r->shader.find('\r'), std::string::npos);
  EXPECT_TRUE(r->warnings.empty());
}

TEST(BrdfParser, NoAnalyticLineAndExplorerCommentsInShader) {
  // The Explorer dropped '#' lines everywhere; its files may have them inside the shader.
  Result<BrdfDefinition> r = parseBrdf(
      "::begin shader\n"
      "# an Explorer-style comment\n"
      "#define TWO 2.0\n"
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(TWO); }\n"
      "::end shader\n");
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->shaderFirstLine, 2);
  EXPECT_EQ(r->shader,
            "\n#define TWO 2.0\n"
            "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(TWO); }\n");
}

TEST(BrdfParser, IncludeIsAnErrorOnItsLineNotADroppedComment) {
  // '#include' used to be blanked as an Explorer '#' comment, without a word.
  for (const char* include : {"#include \"common.glsl\"", "  # include <lib.glsl>"})
    expectErrorAt(std::string("analytic\n::begin shader\n") + include +
                      "\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1); }\n::end shader\n",
                  3, "terms/<name>.glsl");
  // Sample sections too.
  expectErrorAt(std::string("::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1); }\n"
                            "::end shader\n::begin sample\n#include \"s.glsl\"\n::end sample\n"),
                5, "terms/<name>.glsl");
}

TEST(BrdfParser, TrailingCommentDoesNotSupplyValues) {
  expectErrorAt(withParam("float roughness 0 # 1 0.5"), 3, "roughness");
}

TEST(BrdfParser, MalformedParameterLines) {
  expectErrorAt(withParam("float roughness 0 x 0.5"), 3, "'x' is not a number");
  expectErrorAt(withParam("float roughness 0"), 3, "float name min max default");
  expectErrorAt(withParam("float roughness 1 0 0.5"), 3, "greater than max");
  expectErrorAt(withParam("float roughness 0 1 2"), 3, "outside");
  expectErrorAt(withParam("color Kd 0.5 0.5"), 3, "color name r g b");
  expectErrorAt(withParam("color Kd 0.5 0.5 1.5"), 3, "outside [0, 1]");
  expectErrorAt(withParam("bool iso 2"), 3, "not 0 or 1");
  expectErrorAt(withParam("bool iso"), 3, "bool name 0|1");
  expectErrorAt(withParam("int n 0 4 1"), 3, "unknown parameter type 'int'");
  expectErrorAt(withParam("float"), 3, "no name");
  expectErrorAt(withParam("float a 0 1 nan"), 3, "not a number");
}

TEST(BrdfParser, FloatWithoutDefaultIsLenient) {
  Result<BrdfDefinition> r = parseBrdf(withParam("float roughness 0.25 1"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_FLOAT_EQ(r->params[0].defaultValue[0], 0.25f);
  ASSERT_EQ(r->warnings.size(), 1u);
  EXPECT_EQ(r->warnings[0].line, 3);
}

TEST(BrdfParser, BadLineInLongerFileCarriesItsOwnLine) {
  std::string text = kLambert;
  text.replace(text.find("bool  isotropic 1"), 17, "bool  isotropic yes");
  expectErrorAt(text, 6, "'yes'");
}

TEST(BrdfParser, DuplicateNameIsAnErrorOnTheSecondLine) {
  std::string text = withParam("float a 0 1 0.5\ncolor b 1 1 1\nbool a 0");
  expectErrorAt(text, 5, "already declared on line 3");
}

TEST(BrdfParser, ReservedNames) {
  expectErrorAt(withParam("float uniform 0 1 0"), 3, "keyword");
  expectErrorAt(withParam("float vec3 0 1 0"), 3, "keyword");
  expectErrorAt(withParam("float sampler2D 0 1 0"), 3, "keyword");
  expectErrorAt(withParam("float gl_Foo 0 1 0"), 3, "gl_");
  expectErrorAt(withParam("float brdfa_x 0 1 0"), 3, "brdfa_");
  expectErrorAt(withParam("float a__b 0 1 0"), 3, "__");
  expectErrorAt(withParam("float 9lives 0 1 0"), 3, "identifier");
  expectErrorAt(withParam("float k-d 0 1 0"), 3, "identifier");
  for (const char* name : {"BRDF", "sampleBRDF", "texCoord", "iTexture0", "iTexture3", "BrdfParams"})
    expectErrorAt(withParam(std::string("float ") + name + " 0 1 0"), 3, "renderer");
  // Near misses are fine.
  EXPECT_TRUE(parseBrdf(withParam("float iTexture4 0 1 0")).ok());
  EXPECT_TRUE(parseBrdf(withParam("float glossy 0 1 0")).ok());
}

TEST(BrdfParser, MissingShaderSection) {
  expectErrorAt("analytic\n::begin parameters\nfloat a 0 1 0\n::end parameters\n", 0, "no '::begin shader'");
}

TEST(BrdfParser, ShaderWithoutBrdfFunction) {
  expectErrorAt("analytic\n::begin shader\nfloat f() { return 1.0; }\n::end shader\n", 2, "does not define");
}

TEST(BrdfParser, BrdfEntryPointDetection) {
  auto shaderOnly = [](const std::string& glsl) { return "::begin shader\n" + glsl + "\n::end shader\n"; };
  EXPECT_TRUE(parseBrdf(shaderOnly("vec3\nBRDF (vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)\n{ return "
                                   "vec3(1); }"))
                  .ok());
  expectErrorAt(shaderOnly("vec3 BRDF2(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1); }"), 1,
                "does not define");
  expectErrorAt(shaderOnly("float BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return 1.0; }"), 1, "does not define");
  expectErrorAt(shaderOnly("myvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return 1.0; }"), 1,
                "does not define");
  expectErrorAt(shaderOnly(""), 1, "does not define");
}

TEST(BrdfParser, LegacyRenderFunctionIsDetected) {
  Result<BrdfDefinition> r = parseBrdf(
      "analytic\n::begin shader\n"
      "vec3 render(vec3 L, vec3 N, vec3 V, vec2 textureCord, mat3 worldToLocal) "
      "{ return vec3(iParameter0); }\n::end shader\n");
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->format, BrdfFormat::Legacy);
  // The engine's sliders it reads become parameters in 0..1.
  ASSERT_EQ(r->params.size(), 1u);
  EXPECT_EQ(r->params[0].name, "iParameter0");

  // A bare GLSL source from the BRDFA Engine, with no sections at all: only the sliders it
  // reads (iParameter3 and iParameter8; iParameter80 is another name).
  Result<BrdfDefinition> bare = parseBrdf(
      "#define PI 3.14159265359\n"
      "vec3 render(vec3 L, vec3 N, vec3 V, vec2 textureCord, mat3 worldToLocal)\n"
      "{ float iParameter80 = 1.0; return vec3(iParameter3 * iParameter8 * iParameter80); }\n");
  ASSERT_TRUE(bare.ok()) << bare.error().message;
  EXPECT_EQ(bare->format, BrdfFormat::Legacy);
  EXPECT_EQ(bare->shaderFirstLine, 1);
  ASSERT_EQ(bare->params.size(), 2u);
  EXPECT_EQ(bare->params[0].name, "iParameter3");
  EXPECT_EQ(bare->params[1].name, "iParameter8");
  for (const BrdfParam& p : bare->params) {
    EXPECT_EQ(p.type, ParamType::Float);
    EXPECT_EQ(p.min, 0.0f);
    EXPECT_EQ(p.max, 1.0f);
  }
}

TEST(BrdfParser, IsFuncSectionIsIgnoredWithAWarning) {
  std::string text = std::string(kLambert) +
                     "::begin isFunc\n"  // 13
                     "this is not even GLSL\n"
                     "::end isFunc\n";
  Result<BrdfDefinition> r = parseBrdf(text);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->warnings.size(), 1u);
  EXPECT_EQ(r->warnings[0].line, 13);
  EXPECT_EQ(r->warnings[0].severity, "warning");
  EXPECT_NE(r->warnings[0].message.find("isFunc"), std::string::npos);
  EXPECT_EQ(r->shader.find("not even"), std::string::npos);
}

TEST(BrdfParser, SampleSection) {
  std::string text = std::string(kLambert) +
                     "\n"                                                         // 13
                     "::begin sample\n"                                           // 14
                     "vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y,\n"  // 15
                     "                out vec3 L, out float pdf) { L = N; pdf = 1.0; return vec3(1); }\n"
                     "::end sample\n";
  Result<BrdfDefinition> r = parseBrdf(text);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(r->hasSampler());
  EXPECT_EQ(r->sampleFirstLine, 15);
  EXPECT_EQ(r->sampleShader.rfind("vec3 sampleBRDF(", 0), 0u);

  expectErrorAt(std::string(kLambert) + "::begin sample\nfloat f() { return 1.0; }\n::end sample\n", 13, "sampleBRDF");
}

TEST(BrdfParser, SectionStructureErrors) {
  // Sections cannot nest, as in the Explorer.
  expectErrorAt(
      "::begin shader\n"
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1); }\n"
      "::begin sample\n",
      3, "inside the 'shader' section");
  expectErrorAt(
      "::begin shader\n"
      "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1); }\n"
      "::end parameters\n",
      3, "does not close");
  // An unterminated shader section at the end of the file is accepted with a warning.
  Result<BrdfDefinition> r =
      parseBrdf("::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1); }");
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->warnings.size(), 1u);
}

TEST(BrdfParser, UnknownTextOutsideSectionsIsAWarning) {
  std::string text = "bparam something\n" + std::string(kLambert).substr(9);
  Result<BrdfDefinition> r = parseBrdf(text);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->warnings.size(), 1u);
  EXPECT_EQ(r->warnings[0].line, 1);
}

TEST(BrdfParser, ReportsEveryBadLine) {
  Result<BrdfDefinition> r = parseBrdf(withParam("float a 0 1 5\nfloat b 0 1 7"));
  ASSERT_FALSE(r.ok());
  ASSERT_EQ(r.error().diagnostics.size(), 2u);
  EXPECT_EQ(r.error().diagnostics[0].line, 3);
  EXPECT_EQ(r.error().diagnostics[1].line, 4);
}

TEST(Result, ErrorCodeNames) {
  EXPECT_STREQ(errorCodeName(ErrorCode::InvalidArgument), "invalid_argument");
  EXPECT_STREQ(errorCodeName(ErrorCode::NotFound), "not_found");
  EXPECT_STREQ(errorCodeName(ErrorCode::CompileError), "compile_error");
  EXPECT_STREQ(errorCodeName(ErrorCode::Unsupported), "unsupported");
  EXPECT_STREQ(errorCodeName(ErrorCode::DeviceError), "device_error");
  EXPECT_STREQ(errorCodeName(ErrorCode::Internal), "internal");
  EXPECT_STREQ(paramTypeName(ParamType::Float), "float");
  EXPECT_STREQ(paramTypeName(ParamType::Color), "color");
  EXPECT_STREQ(paramTypeName(ParamType::Bool), "bool");
}

}  // namespace
}  // namespace brdfa
