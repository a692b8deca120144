// Shader trees against each other in one run: the same scenes in one renderer per tree,
// their passes interleaved so both see the same machine load (this 2-core VM's load
// changes a pass's time by 1.5x from one minute to the next; runs minutes apart cannot compare
// a change of a few percent). For shader work: `brdfa-bench --only shaders --against DIR[,DIR...]`,
// each DIR holding a modified copy of shaders/.
#include "bench_shader_ab.h"

#include <chrono>
#include <cstdio>
#include <vector>

#include "brdfa/renderer.h"

#include "bench_nonce.h"
#include "bench_renderer.h"
#include "bench_util.h"

namespace brdfa::bench {

int runShaderAbBench(const std::string& sourceDir, const std::vector<std::string>& againstDirs, int rounds) {
  constexpr int kSamples[2] = {1, 16};
  struct Tree {
    std::string dir;
    std::shared_ptr<Renderer> renderer;
    std::unique_ptr<RenderView> views[2];  // kSamples each pass
    std::vector<double> ms[2];
    // A camera move's first pass: the once-per-restart work (raster, clear, background of the
    // whole image) and the preview (RenderSettings::previewPass), background visible.
    std::unique_ptr<RenderView> moving;
    std::vector<double> moveMs;
    // A BRDF edit as the stream shows it: a program new to every cache (the default mis
    // estimator) at 512x512 with a preview (RenderSettings::previewPass): setScene and the
    // preview pass (on a CPU device, by the preview kernel: LocalRenderer::previewKernel), then
    // the first 1-sample pass, whose first submission carries the program's compile (JIT).
    std::unique_ptr<RenderView> editing;
    std::vector<double> editMs, editSetMs, editFirstPassMs;
  };
  std::vector<Tree> trees(1 + againstDirs.size());
  trees[0].dir = sourceDir;
  for (size_t i = 0; i < againstDirs.size(); ++i) trees[1 + i].dir = againstDirs[i];
  for (Tree& t : trees) {
    RendererOptions options;
    options.shaderDir = t.dir + "/shaders";
    options.submissionTargetMs = 0;  // whole passes: the kernels' cost, not the split's
    auto renderer = Renderer::create(options);
    if (!renderer) {
      std::fprintf(stderr, "renderer for %s: %s\n", t.dir.c_str(), renderer.error().message.c_str());
      return 1;
    }
    t.renderer = renderer.value();
    for (int v = 0; v < 2; ++v) {
      auto view = t.renderer->createView();
      if (!view) return 1;
      if (auto set = (*view)->setScene(ggxScene(sourceDir, false, kSamples[v])); !set) {
        std::fprintf(stderr, "%s: %s\n", t.dir.c_str(), set.error().message.c_str());
        return 1;
      }
      for (int i = 0; i < 6; ++i)  // JIT, raster, the ramp of the first passes
        if (!(*view)->renderPass()) return 1;
      t.views[v] = std::move(view.value());
    }
    auto moving = t.renderer->createView();
    if (!moving) return 1;
    t.moving = std::move(moving.value());
    auto editing = t.renderer->createView();
    if (!editing) return 1;
    t.editing = std::move(editing.value());
  }
  const std::string ggx = readText(sourceDir + "/shaders/brdfs/ggx.brdf");
  auto editedScene = [&](int nonce) -> Result<Scene> {
    Scene s = ggxScene(sourceDir, true, 4);
    s.render.sampling = SamplingMode::Mis;
    s.render.previewPass = true;
    auto def = parseBrdf(withUniqueFactor(ggx, "D_GGX(", nonce));
    if (!def) return def.takeError();
    s.objects[0].brdf = std::make_shared<BrdfDefinition>(def.value());
    return s;
  };
  auto movedScene = [&](int step) {
    Scene s = ggxScene(sourceDir, true, 4);
    s.render.previewPass = true;
    s.camera.yaw = float(step % 2) * 2.0f;
    return s;
  };
  for (int i = -1; i < 2 * rounds; ++i) {
    for (int v = 0; v < 2 && i >= 0; ++v)
      for (Tree& t : trees) {
        auto pass = t.views[v]->renderPass();
        if (!pass) return 1;
        t.ms[v].push_back(pass->lastPassMs);
      }
    for (Tree& t : trees) {  // round -1 warms the moving view up
      const auto t0 = std::chrono::steady_clock::now();
      if (!t.moving->setScene(movedScene(i)) || !t.moving->renderPass()) return 1;
      if (i >= 0) t.moveMs.push_back(msSince(t0));
    }
    for (size_t k = 0; k < trees.size() && i < rounds; ++k) {  // round -1 rasterizes; half the rounds
      Tree& t = trees[k];
      const auto t0 = std::chrono::steady_clock::now();
      auto edited = editedScene(int(1000 * k) + i + 1);
      if (!edited || !t.editing->setScene(*edited)) return 1;
      const double setMs = msSince(t0);
      if (!t.editing->renderPass()) return 1;
      const double previewMs = msSince(t0);
      if (!t.editing->renderPass()) return 1;
      if (i >= 0) {
        t.editSetMs.push_back(setMs);
        t.editMs.push_back(previewMs);
        t.editFirstPassMs.push_back(msSince(t0));
      }
    }
  }
  header("Shader trees against A = " + sourceDir + ": GGX sphere, cosine, 512x512, median of " +
         std::to_string(2 * rounds) + " interleaved passes");
  for (int v = 0; v < 2; ++v) {
    const std::string what = ", " + std::to_string(kSamples[v]) + " sample(s)/pass";
    const double a = median(trees[0].ms[v]);
    row("A" + what, a, "ms");
    for (size_t i = 1; i < trees.size(); ++i) {
      const double b = median(trees[i].ms[v]);
      row(trees[i].dir + what, b, "ms", "/ A " + std::to_string(b / a).substr(0, 5));
    }
  }
  for (auto [what, series] : {std::pair{"setScene", &Tree::editSetMs}, std::pair{"+ preview pass", &Tree::editMs},
                              std::pair{"+ first 1-sample pass", &Tree::editFirstPassMs}}) {
    const double e = median(trees[0].*series);
    row(std::string("A, new BRDF program (mis): ") + what, e, "ms");
    for (size_t i = 1; i < trees.size(); ++i)
      row(trees[i].dir + ", new BRDF program: " + what, median(trees[i].*series), "ms",
          "/ A " + std::to_string(median(trees[i].*series) / e).substr(0, 5));
  }
  const double a = median(trees[0].moveMs);
  row("A, camera moved: setScene + preview pass (sky visible)", a, "ms");
  for (size_t i = 1; i < trees.size(); ++i)
    row(trees[i].dir + ", camera moved", median(trees[i].moveMs), "ms",
        "/ A " + std::to_string(median(trees[i].moveMs) / a).substr(0, 5));
  return 0;
}

}  // namespace brdfa::bench
