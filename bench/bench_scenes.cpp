// Scene figures: mesh size must not change the cost of a progressive pass (the
// visibility is rasterized once per camera change), and a scene's program holds only what the
// scene uses.
#include "bench_scenes.h"

#include <chrono>
#include <fstream>
#include <sstream>

#include "brdfa/renderer.h"

#include "bench_nonce.h"
#include "bench_util.h"

namespace brdfa::bench {

namespace {

std::shared_ptr<const BrdfDefinition> brdfFrom(const std::string& text) {
  auto def = parseBrdf(text);
  if (!def) return nullptr;
  return std::make_shared<BrdfDefinition>(def.value());
}

Scene sceneWith(std::shared_ptr<const BrdfDefinition> brdf, const std::string& mesh, int samplesPerPass) {
  Scene s;
  s.environment.name = "sky";
  s.environment.visible = true;
  s.render.samplesPerFrame = samplesPerPass;
  s.render.maxSamples = kMaxTotalSamples;
  SceneObject o;
  o.brdf = std::move(brdf);
  o.mesh = mesh;
  s.objects.push_back(o);
  return s;
}

// Ward's anisotropic lobe over a textured diffuse term: reads X, Y and iTexture0..1, so its
// program carries the tangent frame and the texture bindings a lambert-only one leaves out.
const char* kTexturedWard = R"(analytic
::begin parameters
float alpha_x 0.01 0.5 0.3
float alpha_y 0.01 0.5 0.05
::end parameters
::begin shader
const float PI = 3.14159265358979323846;
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {
    float NoL = dot(N, L), NoV = dot(N, V);
    if (NoL <= 0.0 || NoV <= 0.0) return vec3(0.0);
    vec3 h = L + V;
    float hx = dot(h, X) / alpha_x, hy = dot(h, Y) / alpha_y, hn = dot(h, N);
    float spec = exp(-(hx * hx + hy * hy) / (hn * hn)) / (4.0 * PI * alpha_x * alpha_y * sqrt(NoL * NoV));
    vec3 albedo = texture(iTexture0, texCoord).rgb * texture(iTexture1, texCoord * 4.0).rgb;
    return albedo * (0.5 / PI) + vec3(0.5 * spec * FACTOR);
}
::end shader
)";

struct FirstFrame {
  double setSceneMs = 0, firstPassMs = 0;
  uint64_t programBytes = 0;
};

// A program new to every cache (unique constant), from setScene to the end of the first pass.
FirstFrame firstFrame(Renderer& renderer, const Scene& scene) {
  FirstFrame r;
  auto view = renderer.createView();
  if (!view) return r;
  auto t0 = std::chrono::steady_clock::now();
  if (!(*view)->setScene(scene)) return r;
  r.setSceneMs = msSince(t0);
  auto pass = (*view)->renderPass();
  r.firstPassMs = pass ? pass->lastPassMs : -1;
  r.programBytes = (*view)->stats().programBytes;
  return r;
}

}  // namespace

int runSceneBench(const std::string& sourceDir, int rounds) {
  RendererOptions options;
  options.shaderDir = sourceDir + "/shaders";
  auto renderer = Renderer::create(options);
  if (!renderer) return 1;
  auto ggx = brdfFrom(readText(sourceDir + "/shaders/brdfs/ggx.brdf"));
  if (!ggx) return 1;

  // Same sphere, same pixels: 32k triangles against 511k. Interleaved, after the warm-up passes
  // that rasterize the four anti-aliasing slices.
  constexpr int kSpp = 16;
  std::unique_ptr<RenderView> views[2];
  const char* meshes[2] = {"sphere", "dense_sphere"};
  std::vector<double> firstMs[2], passMs[2];
  for (int v = 0; v < 2; ++v) {
    auto view = (*renderer)->createView();
    if (!view || !(*view)->setScene(sceneWith(ggx, meshes[v], kSpp))) {
      std::fprintf(stderr, "scene bench: cannot set up the %s scene\n", meshes[v]);
      return 1;
    }
    views[v] = std::move(view.value());
    for (int i = 0; i < 8; ++i) {
      auto pass = views[v]->renderPass();
      if (!pass) return 1;
      if (i < 4) firstMs[v].push_back(pass->lastPassMs);  // each rasterizes one slice
    }
  }
  for (int i = 0; i < rounds; ++i)
    for (int v = 0; v < 2; ++v) passMs[v].push_back(views[v]->renderPass().value().lastPassMs);
  const FrameStats dense = views[1]->stats();
  header("Mesh size (GGX, sky, 512x512, 16 samples/pass, median of " + std::to_string(rounds) + " interleaved passes)");
  row("sphere (" + std::to_string(views[0]->stats().triangles) + " triangles) per pass", median(passMs[0]), "ms");
  row("dense_sphere (" + std::to_string(dense.triangles) + " triangles) per pass", median(passMs[1]), "ms");
  row("ratio dense / sphere per pass", median(passMs[1]) / median(passMs[0]), "x", "target <= 1.2");
  row("sphere: passes that rasterize a slice (4 after a camera change)", median(firstMs[0]), "ms");
  row("dense_sphere: passes that rasterize a slice", median(firstMs[1]), "ms");

  // Specialization: the same sphere, lambert only against textures + anisotropy.
  const std::string lambert = readText(sourceDir + "/shaders/brdfs/lambert.brdf");
  std::vector<double> plainFirst, richFirst;
  uint64_t plainBytes = 0, richBytes = 0;
  for (int i = 0; i < 5; ++i) {
    const std::string plain = withUniqueFactor(lambert, "Kd / PI;", 100 + i);
    std::string rich = kTexturedWard;
    rich.replace(rich.find("FACTOR"), 6, uniqueFactor(200 + i));
    Scene a = sceneWith(brdfFrom(plain), "sphere", 4);
    Scene b = sceneWith(brdfFrom(rich), "sphere", 4);
    // One estimator for both, so that the programs differ only in what the BRDFs use: under
    // mis, lambert's program carries its sampler and pdf and ward's does not (41.6 KiB each).
    a.render.sampling = b.render.sampling = SamplingMode::Cosine;
    b.objects[0].textures = {{"checker", true}, {"uv_grid", true}};
    FirstFrame fa = firstFrame(**renderer, a), fb = firstFrame(**renderer, b);
    plainFirst.push_back(fa.setSceneMs + fa.firstPassMs);
    richFirst.push_back(fb.setSceneMs + fb.firstPassMs);
    plainBytes = fa.programBytes;
    richBytes = fb.programBytes;
  }
  header("Specialization (sphere, sky, 512x512, 4 samples/pass, cosine; new programs, median of 5)");
  row("lambert only: program size", plainBytes / 1024.0, "KiB SPIR-V");
  row("textures + anisotropy (ward, 2 textures): program size", richBytes / 1024.0, "KiB SPIR-V");
  row("lambert only: setScene + first pass", median(plainFirst), "ms");
  row("textures + anisotropy: setScene + first pass", median(richFirst), "ms");
  return 0;
}

}  // namespace brdfa::bench
