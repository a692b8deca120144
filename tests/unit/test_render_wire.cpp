// The render worker's wire format (render_wire.h): every value the server and the worker
// exchange comes back equal, NaN and infinities included (a check's worst value may be either).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "isolation/render_wire.h"

namespace brdfa {
namespace {

namespace wire = render_wire;

wire::Message throughTheWire(const wire::Message& m) {
  wire::Message back;
  EXPECT_TRUE(wire::decode(wire::encode(m), back));
  return back;
}

TEST(RenderWire, SceneWithEveryFieldSetComesBackEqual) {
  auto brdf = std::make_shared<BrdfDefinition>();
  brdf->params.push_back(BrdfParam{"Kd", ParamType::Color, 0, 1, {0.25f, 0.5f, 1.0f}, 3});
  brdf->shader = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd / 3.14159; }";
  brdf->shaderFirstLine = 6;
  brdf->sampleShader = "// sampler";
  brdf->sampleFirstLine = 9;
  Scene s;
  s.camera.position = {1, 2, 3};
  s.camera.yaw = 12.5f;
  s.environment.name = "sky";
  s.environment.visible = false;
  s.render.width = 77;
  s.render.sampling = SamplingMode::Environment;
  s.render.toneMap = ToneMap::Aces;
  s.render.targetError = 0.01;
  SceneObject o;
  o.mesh = "teapot";
  o.brdf = brdf;
  o.brdfName = "mine";
  o.params["Kd"] = {0.1f, 0.2f, 0.3f};
  o.rotate = {0, 90, 0};
  o.textures.push_back(TextureBinding{"checker", false});
  s.objects.push_back(o);

  wire::Message m;
  m.head["scene"] = wire::toJson(s);
  const Scene back = wire::sceneFromJson(throughTheWire(m).head.at("scene"));
  EXPECT_EQ(back.camera.position, s.camera.position);
  EXPECT_EQ(back.camera.yaw, 12.5f);
  EXPECT_EQ(back.environment.name, "sky");
  EXPECT_FALSE(back.environment.visible);
  EXPECT_EQ(back.render.width, 77);
  EXPECT_EQ(back.render.sampling, SamplingMode::Environment);
  EXPECT_EQ(back.render.toneMap, ToneMap::Aces);
  EXPECT_EQ(back.render.targetError, 0.01);
  ASSERT_EQ(back.objects.size(), 1u);
  EXPECT_EQ(back.objects[0].mesh, "teapot");
  EXPECT_EQ(back.objects[0].brdfName, "mine");
  EXPECT_EQ(back.objects[0].params.at("Kd"), o.params.at("Kd"));
  EXPECT_EQ(back.objects[0].rotate, o.rotate);
  ASSERT_EQ(back.objects[0].textures.size(), 1u);
  EXPECT_EQ(back.objects[0].textures[0], o.textures[0]);
  ASSERT_TRUE(back.objects[0].brdf);
  EXPECT_EQ(back.objects[0].brdf->shader, brdf->shader);
  EXPECT_EQ(back.objects[0].brdf->sampleFirstLine, 9);
  EXPECT_EQ(back.objects[0].brdf->params[0].defaultValue, brdf->params[0].defaultValue);
  EXPECT_EQ(wire::programKey(*back.objects[0].brdf), wire::programKey(*brdf));
}

TEST(RenderWire, ProgramKeyChangesWithTheCodeAndItsLinesOnly) {
  BrdfDefinition a;
  a.shader = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(0.3); }";
  a.shaderFirstLine = 4;
  BrdfDefinition b = a;
  b.warnings.push_back(Diagnostic{1, 0, "warning", "ignored section"});
  EXPECT_EQ(wire::programKey(a), wire::programKey(b));
  b.shaderFirstLine = 5;  // moves every #line: another program
  EXPECT_NE(wire::programKey(a), wire::programKey(b));
  b = a;
  b.shader += " ";
  EXPECT_NE(wire::programKey(a), wire::programKey(b));
}

TEST(RenderWire, NanAndInfinitySurviveInReports) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  SamplerCheckReport r;
  r.maxCellZ = inf;
  r.worstValue = nan;
  r.chi2PValues = {0.5, nan};
  r.configs.resize(2);
  r.configs[1].config.normalLabel = "near +x";
  r.configs[1].albedoZ = -inf;
  wire::Message m;
  m.head["value"] = wire::toJson(r);
  const SamplerCheckReport back = wire::samplerReportFromJson(throughTheWire(m).head.at("value"));
  EXPECT_TRUE(std::isinf(back.maxCellZ));
  EXPECT_TRUE(std::isnan(back.worstValue));
  ASSERT_EQ(back.chi2PValues.size(), 2u);
  EXPECT_TRUE(std::isnan(back.chi2PValues[1]));
  ASSERT_EQ(back.configs.size(), 2u);
  EXPECT_EQ(back.configs[1].config.normalLabel, "near +x");
  EXPECT_EQ(back.configs[1].albedoZ, -inf);

  FrameStats f;
  f.relError = nan;
  f.spp = 1ull << 40;
  f.estimator = "mis(environment+brdf)";
  f.submissions = 9;
  f.maxSubmissionMs = 51.5;
  m.head["value"] = wire::toJson(f);
  const FrameStats fb = wire::statsFromJson(throughTheWire(m).head.at("value"));
  ASSERT_TRUE(fb.relError.has_value());
  EXPECT_TRUE(std::isnan(*fb.relError));
  EXPECT_EQ(fb.spp, 1ull << 40);
  EXPECT_EQ(fb.estimator, f.estimator);
  EXPECT_EQ(fb.submissions, 9u);
  EXPECT_EQ(fb.maxSubmissionMs, 51.5);
  f.relError.reset();
  m.head["value"] = wire::toJson(f);
  EXPECT_FALSE(wire::statsFromJson(throughTheWire(m).head.at("value")).relError.has_value());
}

TEST(RenderWire, BinaryTailAndErrorsComeBackWhole) {
  wire::Message m;
  m.head["id"] = 7;
  m.tail = std::string("\0\x01\xff pixels", 10);
  Error e = makeError(ErrorCode::RenderBudget, "quarantined", "objects[0].brdf");
  e.diagnostics.push_back(Diagnostic{3, 4, "error", "budget"});
  m.head["error"] = wire::toJson(e);
  const wire::Message back = throughTheWire(m);
  EXPECT_EQ(back.tail, m.tail);
  EXPECT_EQ(back.head.at("id"), 7);
  const Error eb = wire::errorFromJson(back.head.at("error"));
  EXPECT_EQ(eb.code, ErrorCode::RenderBudget);
  EXPECT_EQ(eb.field, "objects[0].brdf");
  ASSERT_EQ(eb.diagnostics.size(), 1u);
  EXPECT_EQ(eb.diagnostics[0].column, 4);

  wire::Message garbled;
  EXPECT_FALSE(wire::decode(std::string("\x05\0\0\0ab", 6), garbled));  // shorter than it says
}

}  // namespace
}  // namespace brdfa
