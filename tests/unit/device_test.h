// What the unit tests on the real Vulkan device share: one renderer per test suite over the
// source tree's shaders, and BRDF files parsed from the built-in library or from text.
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "brdfa/renderer.h"

namespace brdfa {

// A whole file of the source tree ("" when it cannot be read).
inline std::string readSourceFile(const std::string& relative) {
  std::ifstream in(std::string(BRDFA_SOURCE_DIR) + "/" + relative);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A `.brdf` text parsed; a parse error fails the calling test.
inline std::shared_ptr<const BrdfDefinition> inlineBrdf(const std::string& text) {
  auto def = parseBrdf(text);
  EXPECT_TRUE(def.ok()) << (def.ok() ? "" : def.error().message);
  return def.ok() ? std::make_shared<BrdfDefinition>(def.value()) : nullptr;
}

// shaders/brdfs/<name>.brdf parsed.
inline std::shared_ptr<const BrdfDefinition> builtin(const std::string& name) {
  return inlineBrdf(readSourceFile("shaders/brdfs/" + name + ".brdf"));
}

// A white Lambertian (f = Kd / pi, Kd = 1): renders as 1.0 in the furnace.
inline constexpr const char* kWhiteLambert = R"(analytic
::begin parameters
color Kd 1 1 1
::end parameters
::begin shader
const float PI = 3.14159265358979323846;
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd / PI; }
::end shader
)";

// Runs passes until the view is done (converged or max_samples reached), every pass
// succeeding, and reads the frame with linear radiance.
inline Frame renderUntilDone(RenderView& view) {
  for (int guard = 0; guard < 1000000; ++guard) {
    auto pass = view.renderPass();
    EXPECT_TRUE(pass.ok());
    if (!pass.ok() || pass->done()) break;
  }
  auto frame = view.readFrame(true);
  EXPECT_TRUE(frame.ok());
  return frame.ok() ? frame.value() : Frame{};
}

// A new view of `renderer` showing `scene`. Null (with the failure reported) when the view or
// the scene cannot be made.
inline std::unique_ptr<RenderView> viewWithScene(Renderer& renderer, const Scene& scene) {
  auto view = renderer.createView();
  EXPECT_TRUE(view.ok());
  if (!view.ok()) return nullptr;
  auto set = view.value()->setScene(scene);
  EXPECT_TRUE(set.ok()) << (set.ok() ? "" : set.error().message);
  return set.ok() ? std::move(view.value()) : nullptr;
}

// A fixture whose suite shares one renderer (the device opens once per suite).
class DeviceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    RendererOptions options;
    options.shaderDir = std::string(BRDFA_SOURCE_DIR) + "/shaders";
    auto r = Renderer::create(options);
    ASSERT_TRUE(r.ok()) << r.error().message;
    renderer_ = r.value();
  }
  static void TearDownTestSuite() { renderer_.reset(); }

  static inline std::shared_ptr<Renderer> renderer_;
};

}  // namespace brdfa
