// Renderer-level figures: shading throughput against the minimal reference kernel (interleaved
// pass by pass in one run, so both see the same machine load), compile and first-draw times,
// and PNG encoding.
#include "bench_renderer.h"

#include <chrono>
#include <fstream>
#include <sstream>

#include "brdfa/image_codec.h"
#include "brdfa/renderer.h"

#include "bench_nonce.h"
#include "bench_util.h"
#include "minimal_kernel.h"

namespace brdfa::bench {

namespace {

double mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? 0 : sum / double(v.size());
}

// Where a pass's time goes: the hidden-background view's scene again, in a renderer with
// RendererOptions::profilePasses (each phase its own timed submission) and without splitting,
// interleaved with `plain` (the same scene in the benchmark's renderer, alone, so unsplit too).
// The shade kernel's time is split into a per-pixel fixed part and the samples' part by a second
// profiled view at 1 sample/pass: fixed = shade(1) - perSample, perSample = (shade(16) -
// shade(1)) / 15. Means, not medians, so that the parts add up: the error estimate's resolve
// runs every ~200 ms, not every pass.
int passBreakdown(const std::string& sourceDir, int rounds, RenderView& plain) {
  RendererOptions options;
  options.shaderDir = sourceDir + "/shaders";
  options.profilePasses = true;
  options.submissionTargetMs = 0;
  auto renderer = Renderer::create(options);
  if (!renderer) return 1;
  std::unique_ptr<RenderView> views[2];  // 16 and 1 samples/pass
  for (int v = 0; v < 2; ++v) {
    auto view = (*renderer)->createView();
    if (!view || !(*view)->setScene(ggxScene(sourceDir, false, v == 0 ? 16 : 1))) return 1;
    for (int i = 0; i < 6; ++i)
      if (!(*view)->renderPass()) return 1;
    views[v] = std::move(view.value());
  }
  std::vector<double> setup, shade, edge, resolve, other, shadeOne, plainMs;
  for (int i = 0; i < 2 * rounds; ++i) {
    auto p = views[0]->renderPass();
    auto one = views[1]->renderPass();
    auto q = plain.renderPass();
    if (!p || !one || !q) return 1;
    const PassBreakdown& b = p->breakdown;
    setup.push_back(b.setupMs);
    shade.push_back(b.shadeMs);
    edge.push_back(b.edgeMs);
    resolve.push_back(b.resolveMs);
    other.push_back(b.otherMs);
    shadeOne.push_back(one->breakdown.shadeMs);
    plainMs.push_back(q->lastPassMs);
  }
  const double perSample = (mean(shade) - mean(shadeOne)) / 15;
  header("Where a pass's time goes: GGX sphere, sky, background hidden, 512x512, 16 samples/pass, mean of " +
         std::to_string(2 * rounds) + " profiled passes");
  row("G-buffer raster, clears, background (pending only)", mean(setup), "ms");
  row("shade kernel", mean(shade), "ms");
  row("  per-pixel fixed part (G-buffer, frame, accumulators)", mean(shadeOne) - perSample, "ms",
      "from a 1 sample/pass view");
  row("  16 samples", 16 * perSample, "ms", std::to_string(perSample).substr(0, 5) + " ms per sample");
  row("edge kernel (background samples of edge pixels)", mean(edge), "ms");
  row("error estimate resolve (every ~200 ms)", mean(resolve), "ms");
  row("recording, submissions, fence waits", mean(other), "ms");
  const double parts = mean(setup) + mean(shade) + mean(edge) + mean(resolve) + mean(other);
  row("sum of the parts (= profiled pass)", parts, "ms");
  row("pass time measured without profiling", mean(plainMs), "ms");
  row("sum of the parts / measured pass", 100.0 * parts / mean(plainMs), "%", "within 90..110");
  return 0;
}

}  // namespace

Scene ggxScene(const std::string& sourceDir, bool visibleBackground, int samplesPerPass) {
  auto def = parseBrdf(readText(sourceDir + "/shaders/brdfs/ggx.brdf"));
  Scene s;
  s.environment.name = "sky";
  s.environment.visible = visibleBackground;
  s.render.samplesPerFrame = samplesPerPass;
  s.render.maxSamples = kMaxTotalSamples;
  s.render.sampling = SamplingMode::Cosine;  // the reference kernel's estimator
  SceneObject o;
  o.brdf = std::make_shared<BrdfDefinition>(def.value());
  s.objects.push_back(o);
  return s;
}

int runRendererBench(const std::string& sourceDir, int rounds) {
  RendererOptions options;
  options.shaderDir = sourceDir + "/shaders";
  auto renderer = Renderer::create(options);
  if (!renderer) {
    std::fprintf(stderr, "renderer: %s\n", renderer.error().message.c_str());
    return 1;
  }
  std::printf("device: %s (%s), %s\n", (*renderer)->device().name.c_str(), (*renderer)->device().type.c_str(),
              (*renderer)->device().driver.c_str());

  constexpr int kSize = 512, kSpp = 16;
  auto reference = MinimalKernel::create(sourceDir, kSize, kSize);
  if (!reference) {
    std::fprintf(stderr, "reference kernel: %s\n", reference.error().message.c_str());
    return 1;
  }
  std::unique_ptr<RenderView> views[2];
  for (int v = 0; v < 2; ++v) {
    auto view = (*renderer)->createView();
    if (!view || !(*view)->setScene(ggxScene(sourceDir, v == 1, kSpp))) {
      std::fprintf(stderr, "view setup failed\n");
      return 1;
    }
    views[v] = std::move(view.value());
  }
  // Warm-up: JIT of every kernel, the one-time raster pass, and the ramp of the first passes
  // after a restart (1, 2, 4, ... samples) up to the full 16.
  if (!(*reference)->pass(kSpp)) return 1;
  for (auto& view : views)
    for (int i = 0; i < 6; ++i)
      if (!view->renderPass()) return 1;
  std::vector<double> refMs, hiddenMs, visibleMs;
  for (int i = 0; i < rounds; ++i) {
    refMs.push_back((*reference)->pass(kSpp).value());
    hiddenMs.push_back(views[0]->renderPass().value().lastPassMs);
    visibleMs.push_back(views[1]->renderPass().value().lastPassMs);
  }
  const double samples = double(spherePixels(kSize, kSize)) * kSpp;
  auto mps = [&](double ms) { return samples / (ms * 1e3); };
  header("Shading throughput: GGX sphere, sky cubemap, 512x512, 16 samples/pass, median of " + std::to_string(rounds) +
         " interleaved passes");
  row("minimal reference kernel (bench/minimal_kernel.glsl)", mps(median(refMs)), "M samples/s",
      std::to_string(median(refMs)).substr(0, 6) + " ms/pass");
  row("renderer, background hidden", mps(median(hiddenMs)), "M samples/s",
      std::to_string(median(hiddenMs)).substr(0, 6) + " ms/pass");
  row("renderer, background visible", mps(median(visibleMs)), "M samples/s",
      std::to_string(median(visibleMs)).substr(0, 6) + " ms/pass");
  row("ratio renderer / reference (hidden)", 100.0 * median(refMs) / median(hiddenMs), "%", "target >= 80");
  row("ratio renderer / reference (visible)", 100.0 * median(refMs) / median(visibleMs), "%", "target >= 80");

  if (int code = passBreakdown(sourceDir, rounds, *views[0]); code != 0) return code;

  // A new BRDF each time (a changed constant, so neither glslang's nor the driver's caches hit).
  std::vector<double> compileMs, firstPassMs, setSceneMs;
  const std::string lambert = readText(sourceDir + "/shaders/brdfs/lambert.brdf");
  for (int i = 0; i < 5; ++i) {
    auto def = parseBrdf(withUniqueFactor(lambert, "Kd / PI;", i));
    if (!def) {
      std::fprintf(stderr, "the edited lambert.brdf: %s\n", def.error().message.c_str());
      return 1;
    }
    auto t0 = std::chrono::steady_clock::now();
    auto info = (*renderer)->compileBrdf(def.value());
    compileMs.push_back(info ? info->compileMs : -1);
    Scene s = ggxScene(sourceDir, true, 4);
    s.objects[0].brdf = std::make_shared<BrdfDefinition>(def.value());
    auto view = (*renderer)->createView();
    auto t1 = std::chrono::steady_clock::now();
    if (!(*view)->setScene(s)) return 1;
    setSceneMs.push_back(msSince(t1));
    auto pass = (*view)->renderPass();
    firstPassMs.push_back(pass ? pass->lastPassMs : -1);
    (void)t0;
  }
  header("New BRDF: compile and first draw (lambert variants, 512x512, 4 samples/pass, median of 5)");
  row("glslang compile (in process)", median(compileMs), "ms");
  row("setScene with the new BRDF (pipeline creation)", median(setSceneMs), "ms");
  row("first pass (driver JIT + raster + shading)", median(firstPassMs), "ms");

  auto frame = views[1]->readFrame(false);
  if (!frame) return 1;
  std::vector<double> pngMs;
  size_t pngBytes = 0;
  for (int i = 0; i < 20; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    auto png = encodePng(frame->rgba8.data(), frame->width, frame->height);
    pngMs.push_back(msSince(t0));
    pngBytes = png.size();
  }
  std::vector<double> readMs;
  for (int i = 0; i < 10; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    if (!views[1]->readFrame(false)) return 1;
    readMs.push_back(msSince(t0));
  }
  header("Frames (512x512, GGX in the sky)");
  row("resolve + readback (tone-mapped RGBA8)", median(readMs), "ms");
  row("PNG encode (libdeflate level 1, Sub filter)", median(pngMs), "ms", std::to_string(pngBytes / 1024) + " KiB");
  return 0;
}

}  // namespace brdfa::bench
