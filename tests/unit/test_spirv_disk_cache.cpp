// The SPIR-V disk cache: keyed by content and compiler, survives a restart, can be bypassed,
// and treats a corrupt file as a miss.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "brdfa/renderer.h"

namespace brdfa {
namespace {

std::string uniqueLambert() {
  // A constant unique to this run, so no earlier cache content can match.
  auto now = std::chrono::steady_clock::now().time_since_epoch().count() % 1000003;
  return "analytic\n::begin parameters\ncolor Kd 1 1 1\n::end parameters\n::begin shader\n"
         "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return Kd * " +
         std::to_string(0.3 + 1e-9 * double(now)) + "; }\n::end shader\n";
}

std::shared_ptr<Renderer> rendererWith(const std::string& cacheDir, bool load) {
  RendererOptions options;
  options.shaderDir = std::string(BRDFA_SOURCE_DIR) + "/shaders";
  options.cacheDir = cacheDir;
  options.loadCache = load;
  return Renderer::create(options).value();
}

TEST(SpirvDiskCache, SurvivesARestartIsBypassableAndToleratesCorruption) {
  const auto dir = std::filesystem::temp_directory_path() / ("brdfa-spirv-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  BrdfDefinition brdf = parseBrdf(uniqueLambert()).value();

  auto first = rendererWith(dir.string(), true);
  const uint64_t compilesBefore = first->counters().glslCompiles;
  ASSERT_TRUE(first->compileBrdf(brdf).ok());
  EXPECT_EQ(first->counters().glslCompiles, compilesBefore + 1);
  first.reset();

  auto second = rendererWith(dir.string(), true);  // a restart: memory cache empty
  const RendererCounters c0 = second->counters();
  auto info = second->compileBrdf(brdf);
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(second->counters().glslCompiles, c0.glslCompiles) << "served from disk, not compiled";
  EXPECT_EQ(second->counters().spirvDiskHits, c0.spirvDiskHits + 1);
  second.reset();

  auto bypass = rendererWith(dir.string(), false);  // --no-cache-load
  const uint64_t c1 = bypass->counters().glslCompiles;
  ASSERT_TRUE(bypass->compileBrdf(brdf).ok());
  EXPECT_EQ(bypass->counters().glslCompiles, c1 + 1);
  bypass.reset();

  for (const auto& entry : std::filesystem::directory_iterator(dir)) {  // corrupt every entry
    std::ofstream out(entry.path(), std::ios::binary | std::ios::trunc);
    out << "not spir-v";
  }
  auto afterCorruption = rendererWith(dir.string(), true);
  const uint64_t c2 = afterCorruption->counters().glslCompiles;
  ASSERT_TRUE(afterCorruption->compileBrdf(brdf).ok());
  EXPECT_EQ(afterCorruption->counters().glslCompiles, c2 + 1) << "a corrupt entry is a miss";
  afterCorruption.reset();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace brdfa
