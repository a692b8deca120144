// The scene a RenderView draws: the resolved form of docs/design.md's scene JSON.
// Names (mesh, environment) are resolved by the renderer; BRDFs arrive already parsed.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "brdfa/brdf.h"

namespace brdfa {

struct Camera {
  Vec3 position{0, 0, 3};
  float yaw = 0;    // degrees, about +Y; 0 looks down -Z
  float pitch = 0;  // degrees, about the camera's X axis; positive looks up
  float fov = 45;   // vertical field of view, degrees
};

struct EnvironmentSettings {
  std::string name = "furnace";
  float intensity = 1.0f;
  float rotation = 0.0f;  // degrees about +Y
  bool visible = true;    // drawn as the background
};

// How the integrator draws directions. All are unbiased: f * L * cos / pdf.
//   Cosine, Uniform: over the hemisphere. Brdf: the file's own sampleBRDF() (importance
//   sampling); for a BRDF without a `::begin sample` section it falls back to Cosine.
//   Environment: directions drawn in proportion to the environment's luminance (over the whole
//   sphere; a constant environment draws uniformly). Mis: multiple importance sampling of the
//   environment and the BRDF side (the file's sampler when it also defines pdfBRDF, else
//   cosine), Veach 1997's balance heuristic over a deterministic mixture; in a constant
//   environment it is the BRDF side alone (the environment adds no shape to the integrand).
// Legacy render() files always run the BRDFA Engine's estimator, whatever the mode.
enum class SamplingMode { Cosine, Uniform, Brdf, Environment, Mis };
// "cosine" | "uniform" | "brdf" | "environment" | "mis"
const char* samplingModeName(SamplingMode mode);
bool samplingModeFromName(const std::string& name, SamplingMode& mode);  // false if unknown

// Display mapping of linear radiance L (after exposure, e = L * 2^exposure) before the sRGB
// encoding of PNG frames; float outputs (PFM, EXR) are never tone mapped.
//   Clamp:    min(e, 1);
//   Reinhard: e / (1 + e), per channel (Reinhard et al. 2002, eq. 3);
//   Aces:     Narkowicz's 2015 fit of the ACES filmic curve, per channel.
enum class ToneMap { Clamp, Reinhard, Aces };
const char* toneMapName(ToneMap toneMap);                         // "clamp" | "reinhard" | "aces"
bool toneMapFromName(const std::string& name, ToneMap& toneMap);  // false if unknown

struct RenderSettings {
  int width = 512;
  int height = 512;
  int samplesPerFrame = 4;
  int maxSamples = 4096;
  SamplingMode sampling = SamplingMode::Mis;
  // Rendering stops once rel_error <= targetError (FrameStats::converged); 0 means no target.
  double targetError = 0;
  // Picks the random shifts of every pixel's sample sequences: renders of one scene with
  // different seeds are statistically independent estimates (references, replicates); the
  // same seed renders the same image. A change restarts accumulation.
  uint32_t seed = 0;
  float exposure = 0.0f;  // stops; PNG = sRGB(tonemap(L * 2^exposure))
  ToneMap toneMap = ToneMap::Clamp;
  // Not part of the scene JSON: set by interactive users (the server's sessions). After each
  // restart of accumulation, in images of at least kPreviewMinPixels, a preview pass comes
  // first: one sample at one pixel of every 2x2 block, shown in the whole block
  // (FrameStats::preview), for about a quarter of a 1-sample pass's cost. The first real pass
  // overwrites it; it counts in no sample count, error estimate or pass count. Changing it
  // alone changes nothing in the image.
  bool previewPass = false;
  static constexpr uint64_t kPreviewMinPixels = 256 * 256;
  // Not part of the scene JSON either. On a device that compiles a program at its first
  // dispatch (lavapipe), the first pass after a restart whose programs have not run yet takes
  // one sample per pixel by the small preview kernel (cosine directions, the exact
  // environment) instead of waiting for the programs' compile: a 1-sample estimate of the
  // image (FrameStats::provisional), in place of a preview. The first pass by the programs
  // replaces it, and the sample count starts again from that pass: the scene's own estimator
  // alone makes the image that converges.
  bool firstSampleKernel = false;
};

// One texture slot of an object (iTexture0..3 in order). `name` is a built-in texture or an
// uploaded asset id. sRGB images are decoded to linear values when sampled; linear ones
// (normal maps, roughness) are read as stored.
struct TextureBinding {
  std::string name;
  bool srgb = true;
  bool operator==(const TextureBinding& o) const { return name == o.name && srgb == o.srgb; }
};
inline constexpr int kMaxTextures = 4;

struct SceneObject {
  std::string mesh = "sphere";
  std::shared_ptr<const BrdfDefinition> brdf;  // required
  std::string brdfName;                        // for reports only
  std::map<std::string, Vec3> params;          // missing names take the file's defaults
  Vec3 translate{0, 0, 0};
  Vec3 rotate{0, 0, 0};  // degrees, applied X then Y then Z
  Vec3 scale{1, 1, 1};
  std::vector<TextureBinding> textures;  // at most kMaxTextures; missing slots read white
};

struct Scene {
  Camera camera;
  EnvironmentSettings environment;
  std::vector<SceneObject> objects;
  RenderSettings render;
};

// Limits the renderer enforces in RenderView::setScene (the server checks them earlier too,
// to name the JSON field).
inline constexpr int kMinImageSize = 16;
inline constexpr int kMaxImageSize = 4096;
inline constexpr int kMaxSamplesPerFrame = 1024;
inline constexpr int kMaxTotalSamples = 1 << 20;
inline constexpr int kMaxObjects = 64;
// render.target_error is judged only from this many samples per pixel on (see FrameStats::converged).
inline constexpr uint64_t kMinSppForTarget = 16;
inline constexpr float kMaxPitch = 89.0f;  // degrees; camera pitch is clamped to +-this

}  // namespace brdfa
