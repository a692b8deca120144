// The cost of splitting passes into submissions of about RendererOptions::submissionTargetMs
// for a normal scene: two renderers in one process, one splitting (the default
// target) and one not (target 0), their passes interleaved so both see the same machine load.
#include "bench_split.h"

#include "brdfa/renderer.h"

#include "bench_util.h"
#include "minimal_kernel.h"

namespace brdfa::bench {

namespace {

Scene normalScene(const std::string& sourceDir, const std::string& brdf, int samplesPerPass) {
  auto def = parseBrdf(readText(sourceDir + "/shaders/brdfs/" + brdf + ".brdf"));
  Scene s;
  s.environment.name = "sky";
  s.render.samplesPerFrame = samplesPerPass;
  s.render.maxSamples = kMaxTotalSamples;
  SceneObject o;
  o.brdf = std::make_shared<BrdfDefinition>(def.value());
  s.objects.push_back(o);
  return s;
}

}  // namespace

int runSplitBench(const std::string& sourceDir, int rounds) {
  constexpr int kSize = 512;
  const double targets[2] = {RendererOptions{}.submissionTargetMs, 0.0};
  std::shared_ptr<Renderer> renderers[2];
  for (int k = 0; k < 2; ++k) {
    RendererOptions options;
    options.shaderDir = sourceDir + "/shaders";
    options.submissionTargetMs = targets[k];
    auto r = Renderer::create(options);
    if (!r) {
      std::fprintf(stderr, "renderer: %s\n", r.error().message.c_str());
      return 1;
    }
    renderers[k] = r.value();
  }
  for (const char* brdf : {"ggx", "lambert"})
    for (int spp : {16, 64}) {
      std::unique_ptr<RenderView> views[2];
      for (int k = 0; k < 2; ++k) {
        auto view = renderers[k]->createView();
        if (!view || !(*view)->setScene(normalScene(sourceDir, brdf, spp))) return 1;
        views[k] = std::move(view.value());
        for (int i = 0; i < 8; ++i)  // JIT, raster, the ramp up to spp, and the cost measured
          if (!views[k]->renderPass()) return 1;
      }
      std::vector<double> passMs[2], submissions[2];
      for (int i = 0; i < rounds; ++i)
        for (int k = 0; k < 2; ++k) {
          auto pass = views[k]->renderPass();
          if (!pass) return 1;
          passMs[k].push_back(pass->lastPassMs);
          submissions[k].push_back(double(pass->submissions));
        }
      // A parameter change restarts with the cost unmeasured: the first pass (1 sample) probes.
      std::vector<double> firstMs[2];
      for (int i = 0; i < rounds; ++i)
        for (int k = 0; k < 2; ++k) {
          Scene s = normalScene(sourceDir, brdf, spp);
          s.objects[0].params[brdf == std::string("ggx") ? "roughness" : "Kd"] = {0.2f + 0.01f * i, 0.5f, 0.5f};
          if (!views[k]->setScene(s)) return 1;
          auto pass = views[k]->renderPass();
          if (!pass) return 1;
          firstMs[k].push_back(pass->lastPassMs);
        }
      const double samples = double(spherePixels(kSize, kSize)) * spp;
      auto mps = [&](double ms) { return samples / (ms * 1e3); };
      header(std::string("Pass split: ") + brdf + " sphere, sky, mis, 512x512, " + std::to_string(spp) +
             " samples/pass, median of " + std::to_string(rounds) + " interleaved passes");
      row("split (target " + std::to_string(int(targets[0])) + " ms)", mps(median(passMs[0])), "M samples/s",
          std::to_string(median(passMs[0])).substr(0, 6) + " ms/pass, " +
              std::to_string(median(submissions[0])).substr(0, 4) + " submissions");
      row("unsplit (target 0)", mps(median(passMs[1])), "M samples/s",
          std::to_string(median(passMs[1])).substr(0, 6) + " ms/pass");
      // Each round's two passes ran back to back, under about the same load from elsewhere.
      std::vector<double> ratios;
      for (int i = 0; i < rounds; ++i) ratios.push_back(100.0 * passMs[1][i] / passMs[0][i]);
      row("throughput split / unsplit, median of per-round ratios", median(ratios), "%");
      row("first pass after a parameter change, split", median(firstMs[0]), "ms");
      row("first pass after a parameter change, unsplit", median(firstMs[1]), "ms");
    }
  return 0;
}

}  // namespace brdfa::bench
