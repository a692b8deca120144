// The preview kernel (LocalRenderer::shadeKernels, shaders/kernels/preview.comp.glsl): where the
// device compiles a pipeline at its first dispatch (lavapipe), a new program's preview comes from
// a small kernel, one cosine sample per 2x2 block over the coarse environment
// (environment_preview.h), while the program itself compiles in the first pass. It runs in three
// stages, of which only the middle one holds the BRDF, handing over through a scratch buffer. The preview
// must be the integral it claims (exactly 1 for a white Lambertian in the furnace, the
// converged image's level under the sky with its sun far above 1) and leave no trace in the
// image that follows; the two programs compile once each, and a program that has run previews
// itself.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "brdfa/renderer.h"

#include "assets/environment_preview.h"
#include "device_test.h"

namespace brdfa {
namespace {

std::shared_ptr<Renderer> freshRenderer() {
  RendererOptions options;
  options.shaderDir = std::string(BRDFA_SOURCE_DIR) + "/shaders";
  auto r = Renderer::create(options);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? r.value() : nullptr;
}

// One sphere under `environment` (not seen), mis, with a preview, 256x256 (kPreviewMinPixels).
Scene sphereScene(std::shared_ptr<const BrdfDefinition> brdf, const std::string& environment, int maxSamples) {
  Scene s;
  s.environment.name = environment;
  s.environment.visible = false;
  s.render.width = s.render.height = 256;
  s.render.samplesPerFrame = 8;
  s.render.maxSamples = maxSamples;
  s.render.previewPass = true;
  SceneObject o;
  o.brdf = std::move(brdf);
  s.objects.push_back(o);
  return s;
}

// The first pass, which must be the preview, read as linear radiance.
Frame previewOf(RenderView& view) {
  auto pass = view.renderPass();
  EXPECT_TRUE(pass.ok());
  EXPECT_TRUE(pass.ok() && pass->preview);
  EXPECT_TRUE(pass.ok() && pass->spp == 0);
  auto frame = view.readFrame(true);
  EXPECT_TRUE(frame.ok());
  return frame.ok() ? frame.value() : Frame{};
}

float red(const Frame& f, int x, int y) { return f.rgba32f[4 * (size_t(y) * f.width + x)]; }

// 2x2 blocks all of whose pixels `f` shows lit (inside the object in the preview's G-buffer
// slice), and of those, the ones whose four pixels are not all equal.
void countBlocks(const Frame& f, size_t& inside, size_t& varying) {
  inside = varying = 0;
  for (int y = 0; y + 1 < f.height; y += 2)
    for (int x = 0; x + 1 < f.width; x += 2) {
      const float v = red(f, x, y);
      if (v <= 0 || red(f, x + 1, y) <= 0 || red(f, x, y + 1) <= 0 || red(f, x + 1, y + 1) <= 0) continue;
      ++inside;
      varying += red(f, x + 1, y) != v || red(f, x, y + 1) != v || red(f, x + 1, y + 1) != v;
    }
}

bool cpuDevice(Renderer& r) { return r.device().type == "cpu"; }

TEST(PreviewKernel, ANewProgramsPreviewIsExactInTheFurnaceAndLeavesNoTrace) {
  auto renderer = freshRenderer();
  ASSERT_TRUE(renderer);
  if (!cpuDevice(*renderer)) GTEST_SKIP() << "a GPU compiles at pipeline creation: no preview kernel";
  const Scene scene = sphereScene(inlineBrdf(kWhiteLambert), "furnace", 24);
  const RendererCounters c0 = renderer->counters();
  std::unique_ptr<RenderView> view = viewWithScene(*renderer, scene);
  ASSERT_TRUE(view);
  // The program and its preview kernel, each compiled once (their GLSL side by side).
  EXPECT_EQ(renderer->counters().pipelinesCreated, c0.pipelinesCreated + 2);
  EXPECT_EQ(renderer->counters().glslCompiles, c0.glslCompiles + 2);
  const Frame preview = previewOf(*view);
  const Frame last = renderUntilDone(*view);
  EXPECT_EQ(renderer->counters().pipelinesCreated, c0.pipelinesCreated + 2);
  EXPECT_EQ(renderer->counters().glslCompiles, c0.glslCompiles + 2);

  // The same image without a preview (the program is built now: no preview kernel either way).
  Scene plainScene = scene;
  plainScene.render.previewPass = false;
  std::unique_ptr<RenderView> plain = viewWithScene(*renderer, plainScene);
  ASSERT_TRUE(plain);
  const Frame reference = renderUntilDone(*plain);
  ASSERT_EQ(last.rgba32f.size(), reference.rgba32f.size());
  for (size_t i = 0; i < reference.rgba32f.size(); ++i)
    ASSERT_NEAR(last.rgba32f[i], reference.rgba32f[i], 1e-5f * std::max(1.0f, std::abs(reference.rgba32f[i])))
        << "value " << i;

  // White Lambertian, cosine directions, furnace: every sample is exactly 1, so every object
  // pixel of the preview is (edge pixels mix in the black background at the end, not here).
  size_t ones = 0;
  for (size_t i = 0; i < reference.rgba32f.size(); i += 4) {
    if (std::abs(reference.rgba32f[i] - 1.0f) > 1e-5f) continue;
    ++ones;
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(preview.rgba32f[i + c], 1.0f, 1e-5f) << "pixel " << i / 4;
  }
  EXPECT_GT(ones, 20000u);
}

// A preview hands over through a scratch of 16384 blocks (local_view.cpp): an image of 1022x1000
// (511x500 blocks, rows of workgroups that end mid-group) previews in several dispatches, and two
// objects side by side, overlapping on screen, share the 2x2 blocks along their outline. In the
// furnace, white Lambert (Kd 1) and grey (Kd 0.3): every pixel the converged image shows as one
// object's value (covered in all four G-buffer slices: a pixel covered in some mixes in the
// black background, 0.75, 0.5 or 0.25, or the other object, 0.475 or 0.825) has that value in
// the preview, so no block went missing or took the other object's value.
TEST(PreviewKernel, PreviewsInPiecesAndTwoObjectsSharingBlocksAreExact) {
  auto renderer = freshRenderer();
  ASSERT_TRUE(renderer);
  if (!cpuDevice(*renderer)) GTEST_SKIP() << "a GPU compiles at pipeline creation: no preview kernel";
  Scene scene = sphereScene(inlineBrdf(kWhiteLambert), "furnace", 16);
  scene.render.width = 1022;
  scene.render.height = 1000;
  scene.objects[0].translate = {-0.8f, 0, 0};
  SceneObject grey = scene.objects[0];
  grey.translate = {0.8f, 0, -0.3f};
  grey.params["Kd"] = {0.3f, 0.3f, 0.3f};
  scene.objects.push_back(grey);
  std::unique_ptr<RenderView> view = viewWithScene(*renderer, scene);
  ASSERT_TRUE(view);
  const Frame preview = previewOf(*view);
  const Frame last = renderUntilDone(*view);
  ASSERT_EQ(preview.rgba32f.size(), last.rgba32f.size());
  size_t white = 0, greyPixels = 0;
  for (size_t i = 0; i < last.rgba32f.size(); i += 4) {
    const float v = last.rgba32f[i];
    const bool isWhite = std::abs(v - 1.0f) < 1e-5f, isGrey = std::abs(v - 0.3f) < 1e-5f;
    if (!isWhite && !isGrey) continue;  // background, or an edge mixing slices
    (isWhite ? white : greyPixels) += 1;
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(preview.rgba32f[i + c], isWhite ? 1.0f : 0.3f, 1e-5f)
          << "pixel " << (i / 4) % 1022 << ", " << (i / 4) / 1022;
  }
  // Both spheres are large on screen: each covers several times the blocks of one dispatch's
  // scratch (4 pixels a block).
  EXPECT_GT(white, 4 * 4 * 16384u);
  EXPECT_GT(greyPixels, 4 * 4 * 16384u);
}

// Under the sky (a sun far above 1) the preview is one sample per 2x2 block of the same
// integral over the coarse environment: the mean over the sphere of previews of new programs
// (the same BRDF, a comment apart: each previews by the preview kernel) is the converged
// image's. One preview alone is too noisy for that: ~30 of its samples meet the sun. A view of a
// program that has run previews by the program and builds nothing.
TEST(PreviewKernel, ItsPreviewsUnderTheSkyHaveTheConvergedLevel) {
  auto renderer = freshRenderer();
  ASSERT_TRUE(renderer);
  if (!cpuDevice(*renderer)) GTEST_SKIP() << "a GPU compiles at pipeline creation: no preview kernel";
  for (const char* name : {"lambert", "ggx"}) {
    SCOPED_TRACE(name);
    const std::string text = readSourceFile(std::string("shaders/brdfs/") + name + ".brdf");
    std::unique_ptr<RenderView> reference = viewWithScene(*renderer, sphereScene(inlineBrdf(text), "sky", 512));
    ASSERT_TRUE(reference);
    const Frame converged = renderUntilDone(*reference);
    double convergedSum = 0;
    for (size_t i = 0; i < converged.rgba32f.size(); i += 4)
      for (int c = 0; c < 3; ++c) convergedSum += converged.rgba32f[i + c];

    constexpr int kPreviews = 16;
    double previewSum = 0, brightest = 0;
    for (int k = 0; k < kPreviews; ++k) {
      const uint64_t before = renderer->counters().pipelinesCreated;
      std::string edited = text;
      edited.insert(edited.find("::end shader"), "// preview " + std::to_string(k) + "\n");
      auto brdf = inlineBrdf(edited);
      Scene scene = sphereScene(brdf, "sky", 512);
      scene.render.seed = 1000 + k;
      std::unique_ptr<RenderView> view = viewWithScene(*renderer, scene);
      ASSERT_TRUE(view);
      ASSERT_EQ(renderer->counters().pipelinesCreated, before + 2) << "a new program and its preview kernel";
      const Frame preview = previewOf(*view);
      for (size_t i = 0; i < preview.rgba32f.size(); i += 4)
        for (int c = 0; c < 3; ++c) {
          previewSum += preview.rgba32f[i + c];
          brightest = std::max<double>(brightest, preview.rgba32f[i + c]);
        }
      size_t inside = 0, varying = 0;
      countBlocks(preview, inside, varying);
      EXPECT_GT(inside, 4000u);
      EXPECT_EQ(varying, 0u) << "one value per 2x2 block";
    }
    EXPECT_GT(brightest, 5.0) << "samples that meet the sun far above 1";
    std::printf("%s: mean of %d previews / converged = %.4f, brightest preview value %.1f\n", name, kPreviews,
                previewSum / kPreviews / convergedSum, brightest);
    EXPECT_NEAR(previewSum / kPreviews / convergedSum, 1.0, 0.06);

    const RendererCounters before = renderer->counters();
    std::unique_ptr<RenderView> again = viewWithScene(*renderer, sphereScene(inlineBrdf(text), "sky", 512));
    ASSERT_TRUE(again);
    EXPECT_EQ(renderer->counters().pipelinesCreated, before.pipelinesCreated);
    const Frame byProgram = previewOf(*again);
    size_t inside = 0, varying = 0;
    countBlocks(byProgram, inside, varying);
    EXPECT_GT(inside, 4000u);
    EXPECT_EQ(varying, 0u);
  }
}

// At GGX's roughness extremes (a near-mirror's D of ~1e5 at the peak, and the widest lobe) and
// with the sun far above 1, the preview kernel's preview is finite and non-negative everywhere,
// and lights the sphere.
TEST(PreviewKernel, ItsPreviewAtRoughnessExtremesIsFiniteAndLit) {
  auto renderer = freshRenderer();
  ASSERT_TRUE(renderer);
  if (!cpuDevice(*renderer)) GTEST_SKIP() << "a GPU compiles at pipeline creation: no preview kernel";
  for (float roughness : {0.001f, 1.0f}) {
    SCOPED_TRACE("roughness " + std::to_string(roughness));
    Scene scene = sphereScene(builtin("ggx"), "sky", 1);
    scene.objects[0].params["roughness"] = {roughness, 0, 0};
    const uint64_t before = renderer->counters().pipelinesCreated;
    std::unique_ptr<RenderView> view = viewWithScene(*renderer, scene);
    ASSERT_TRUE(view);
    // The program and its preview kernel, built for the first roughness; the program never
    // runs here (previews only), so the second is previewed by the same preview kernel.
    ASSERT_EQ(renderer->counters().pipelinesCreated, before + (roughness < 0.5f ? 2 : 0));
    const Frame preview = previewOf(*view);
    size_t lit = 0;
    for (size_t i = 0; i < preview.rgba32f.size(); i += 4) {
      for (int c = 0; c < 3; ++c) {
        ASSERT_TRUE(std::isfinite(preview.rgba32f[i + c])) << "pixel " << i / 4;
        ASSERT_GE(preview.rgba32f[i + c], 0.0f) << "pixel " << i / 4;
      }
      lit += preview.rgba32f[i] > 0;
    }
    EXPECT_GT(lit, 10000u);
  }
}

// A first sample (RenderSettings::firstSampleKernel): a new program's first frame is one cosine
// sample per pixel by the preview kernel over the exact environment, counted as spp 1 while
// provisional, and the programs' first pass replaces it. In the furnace a white Lambertian's
// first sample is exactly 1 at every object pixel, also when read as a frame (a read must not
// clear it); with max_samples 1 the view is not done until the program's own sample replaced
// it; and the image that follows is the same as without a first sample.
TEST(PreviewKernel, AFirstSampleIsExactInTheFurnaceAndIsReplaced) {
  auto renderer = freshRenderer();
  ASSERT_TRUE(renderer);
  if (!cpuDevice(*renderer)) GTEST_SKIP() << "a GPU compiles at pipeline creation: no preview kernel";
  for (int maxSamples : {1, 24}) {
    SCOPED_TRACE("max_samples " + std::to_string(maxSamples));
    std::string text = kWhiteLambert;
    text.insert(text.find("::end shader"), "// first sample " + std::to_string(maxSamples) + "\n");
    Scene scene = sphereScene(inlineBrdf(text), "furnace", maxSamples);
    scene.render.firstSampleKernel = true;
    const uint64_t before = renderer->counters().pipelinesCreated;
    std::unique_ptr<RenderView> view = viewWithScene(*renderer, scene);
    ASSERT_TRUE(view);
    ASSERT_EQ(renderer->counters().pipelinesCreated, before + 2) << "a new program and its preview kernel";
    auto first = view->renderPass();
    ASSERT_TRUE(first.ok());
    EXPECT_FALSE(first->preview);
    EXPECT_TRUE(first->provisional);
    EXPECT_EQ(first->spp, 1u);
    EXPECT_EQ(first->passes, 0u);
    EXPECT_FALSE(first->done()) << "the program's own samples are still to come";
    auto frame = view->readFrame(true);
    ASSERT_TRUE(frame.ok());
    EXPECT_EQ(frame->stats.spp, 1u);
    auto second = view->renderPass();
    ASSERT_TRUE(second.ok());
    EXPECT_FALSE(second->provisional);
    EXPECT_EQ(second->passes, 1u);
    EXPECT_EQ(second->spp, 1u) << "the program's first pass replaced the first sample";
    const Frame last = renderUntilDone(*view);

    Scene plainScene = scene;
    plainScene.render.firstSampleKernel = false;
    std::unique_ptr<RenderView> plain = viewWithScene(*renderer, plainScene);
    ASSERT_TRUE(plain);
    const Frame reference = renderUntilDone(*plain);
    ASSERT_EQ(last.rgba32f.size(), reference.rgba32f.size());
    size_t ones = 0;
    for (size_t i = 0; i < reference.rgba32f.size(); ++i)
      ASSERT_NEAR(last.rgba32f[i], reference.rgba32f[i], 1e-5f * std::max(1.0f, std::abs(reference.rgba32f[i])))
          << "value " << i;
    for (size_t i = 0; i < reference.rgba32f.size(); i += 4) {
      if (std::abs(reference.rgba32f[i] - 1.0f) > 1e-5f) continue;
      ++ones;
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(frame->rgba32f[i + c], 1.0f, 1e-5f) << "pixel " << i / 4;
    }
    EXPECT_GT(ones, 20000u);
  }
}

// Under the sky (a sun far above 1) first samples are unbiased 1-sample estimates of the
// image: the mean over the sphere of the first samples of new programs is the converged
// image's, and at GGX's roughness extremes every value is finite and non-negative. Near a
// mirror (roughness 0.001) a cosine direction meets the lobe about once in 10^6 draws, so the
// mean of a few frames says nothing there: only finiteness is asserted.
TEST(PreviewKernel, FirstSamplesUnderTheSkyHaveTheConvergedLevel) {
  auto renderer = freshRenderer();
  ASSERT_TRUE(renderer);
  if (!cpuDevice(*renderer)) GTEST_SKIP() << "a GPU compiles at pipeline creation: no preview kernel";
  const std::string text = readSourceFile("shaders/brdfs/ggx.brdf");
  for (float roughness : {0.001f, 0.3f, 1.0f}) {
    SCOPED_TRACE("roughness " + std::to_string(roughness));
    Scene base = sphereScene(inlineBrdf(text), "sky", 512);
    base.render.previewPass = false;
    base.objects[0].params["roughness"] = {roughness, 0, 0};
    std::unique_ptr<RenderView> reference = viewWithScene(*renderer, base);
    ASSERT_TRUE(reference);
    const Frame converged = renderUntilDone(*reference);
    double convergedSum = 0;
    for (size_t i = 0; i < converged.rgba32f.size(); i += 4)
      for (int c = 0; c < 3; ++c) convergedSum += converged.rgba32f[i + c];
    constexpr int kFirsts = 8;
    double firstSum = 0;
    for (int k = 0; k < kFirsts; ++k) {
      std::string edited = text;
      edited.insert(edited.find("::end shader"),
                    "// first " + std::to_string(k) + " " + std::to_string(roughness) + "\n");
      Scene scene = base;
      scene.objects[0].brdf = inlineBrdf(edited);
      scene.render.firstSampleKernel = true;
      scene.render.seed = 2000 + k;
      std::unique_ptr<RenderView> view = viewWithScene(*renderer, scene);
      ASSERT_TRUE(view);
      auto pass = view->renderPass();
      ASSERT_TRUE(pass.ok() && pass->provisional);
      auto frame = view->readFrame(true);
      ASSERT_TRUE(frame.ok());
      for (size_t i = 0; i < frame->rgba32f.size(); i += 4)
        for (int c = 0; c < 3; ++c) {
          const float v = frame->rgba32f[i + c];
          ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << "pixel " << i / 4;
          firstSum += v;
        }
    }
    std::printf("ggx %.3f: mean of %d first samples / converged = %.4f\n", roughness, kFirsts,
                firstSum / kFirsts / convergedSum);
    if (roughness > 0.01f) EXPECT_NEAR(firstSum / kFirsts / convergedSum, 1.0, 0.06);
  }
}

// Per cell the solid-angle-weighted mean radiance, divided by the cube's scale, in half floats:
// the cells times their solid angles hold the map's integral, a bright texel's energy included.
TEST(EnvironmentPreview, CellsHoldTheMapsIntegralAtTheCubesScale) {
  for (uint32_t size : {64u, 4u}) {  // more texels than cells, and fewer
    SCOPED_TRACE("face size " + std::to_string(size));
    EnvironmentData env;
    env.faceSize = size;
    env.texels.resize(size_t(6) * size * size * 4);
    uint32_t state = 12345;
    double integral[3] = {0, 0, 0};
    for (size_t t = 0; t < env.texels.size() / 4; ++t) {
      for (int c = 0; c < 3; ++c) {
        state = state * 1664525u + 1013904223u;
        env.texels[4 * t + c] = float(state >> 8) / 16777216.0f * (c + 1);
      }
      env.texels[4 * t + 3] = 1;
    }
    env.texels[4 * (size * size * 2 + 1)] = 4.0e5f;  // a sun on +Y, far above the half range
    for (size_t t = 0; t < env.texels.size() / 4; ++t)
      for (int c = 0; c < 3; ++c)
        integral[c] += env.texels[4 * t + c] * cubeTexelSolidAngle(t % size, (t / size) % size, size);
    const float scale = 8.0f;  // what packHalfCube picks for 4e5
    const std::vector<uint32_t> entries = previewRadianceEntries(env, scale);
    ASSERT_EQ(entries.size(), 2 * size_t(kPreviewEntries));
    const uint32_t P = kPreviewCellsPerEdge;
    auto halfToFloat = [](uint32_t h) {
      const uint32_t sign = h >> 15, exponent = (h >> 10) & 31, mantissa = h & 1023;
      const float magnitude =
          exponent == 0 ? std::ldexp(float(mantissa), -24) : std::ldexp(float(mantissa | 1024), int(exponent) - 25);
      return sign ? -magnitude : magnitude;
    };
    double cells[3] = {0, 0, 0};
    for (uint32_t cell = 0; cell < kPreviewEntries; ++cell) {
      const uint32_t x = cell % P, y = (cell / P) % P;
      // A cell's solid angle: its (s, t) square on the face, as the texels of a P-texel face.
      const double omega = cubeTexelSolidAngle(x, y, P);
      const float rgb[3] = {halfToFloat(entries[2 * cell] & 0xffff), halfToFloat(entries[2 * cell] >> 16),
                            halfToFloat(entries[2 * cell + 1] & 0xffff)};
      for (int c = 0; c < 3; ++c) cells[c] += rgb[c] * scale * omega;
    }
    // A cell is the mean of whole texels (64: 4x4 of them), or lies inside one texel (4: each
    // texel covers 4x4 cells): either way the cells tile the texels, and the integral holds to
    // half-float rounding.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(cells[c] / integral[c], 1.0, 2e-3) << "channel " << c;
  }
}

}  // namespace
}  // namespace brdfa
