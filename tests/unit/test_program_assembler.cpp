// Program assembly: std140 parameter block, packing, section order and #line directives.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "program_assembler.h"

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
  ParamBlockLayout l = layoutParams({makeParam("a", ParamType::Float),
                                     makeParam("b", ParamType::Color),
                                     makeParam("c", ParamType::Bool),
                                     makeParam("d", ParamType::Float)});
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

  ParamBlockLayout two = layoutParams({makeParam("a", ParamType::Color),
                                       makeParam("b", ParamType::Color)});
  EXPECT_EQ(two.entries[1].offset, 16u);
  EXPECT_EQ(two.size, 32u);

  std::vector<BrdfParam> five;
  for (const char* n : {"a", "b", "c", "d", "e"}) five.push_back(makeParam(n, ParamType::Float));
  ParamBlockLayout f = layoutParams(five);
  EXPECT_EQ(f.entries[4].offset, 16u);
  EXPECT_EQ(f.size, 32u);

  // float then color: the color must skip to 16, not sit at 4.
  ParamBlockLayout fc = layoutParams({makeParam("a", ParamType::Float),
                                      makeParam("b", ParamType::Color)});
  EXPECT_EQ(fc.entries[1].offset, 16u);
  EXPECT_EQ(fc.size, 32u);
}

TEST(ParamLayout, GlslDeclaration) {
  ParamBlockLayout l = layoutParams({makeParam("roughness", ParamType::Float),
                                     makeParam("Kd", ParamType::Color),
                                     makeParam("iso", ParamType::Bool)});
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
  brdf.params = {makeParam("a", ParamType::Float, {0.25f, 0, 0}),
                 makeParam("b", ParamType::Color, {0.1f, 0.2f, 0.3f}),
                 makeParam("c", ParamType::Bool, {1, 0, 0}),
                 makeParam("d", ParamType::Float, {0.75f, 0, 0})};
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

  std::vector<uint8_t> given = l.pack(brdf, {{"b", {0.9f, 0.8f, 0.7f}}, {"c", {0, 0, 0}},
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
    brdf.shader = "float f() { return roughness; }\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, "
                  "vec3 Y) { return vec3(f()); }";  // no trailing newline on purpose
    brdf.shaderFirstLine = 7;
    spec.brdf = &brdf;
    spec.defines = {"BRDFA_ONE", "BRDFA_TWO 2"};
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

  const size_t block = p.source.find("uniform BrdfParams");
  const size_t chunkA = p.source.find("// chunk A");
  const size_t chunkB = p.source.find("// chunk B");
  const size_t userLine = p.source.find("#line 7 1\nfloat f()");
  const size_t integrator = p.source.find("// integrator");
  ASSERT_NE(userLine, std::string::npos) << p.source;
  EXPECT_LT(block, chunkA);
  EXPECT_LT(chunkA, chunkB);
  EXPECT_LT(chunkB, userLine);
  EXPECT_LT(userLine, integrator);
  // The chunk without a trailing newline must not run into the next one.
  EXPECT_NE(p.source.find("return 1.0; }\n// chunk B"), std::string::npos);

  // `#line k 0` before the integrator names the true line of the line after it.
  for (size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].rfind("#line ", 0) == 0 && lines[i].size() > 2 &&
        lines[i].substr(lines[i].size() - 2) == " 0") {
      const int k = std::stoi(lines[i].substr(6));
      EXPECT_EQ(k, static_cast<int>(i) + 2) << "directive on line " << i + 1;
      ASSERT_LT(i + 1, lines.size());
      EXPECT_EQ(lines[i + 1], "// integrator");
    }
  }
  EXPECT_EQ(p.hash, fnv1a64(p.source));
  EXPECT_EQ(p.params.size, 16u);
}

TEST_F(Assembly, SampleSectionGetsItsOwnLine) {
  brdf.sampleShader = "vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, "
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
