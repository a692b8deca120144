// POST /api/jobs/convergence: one scene rendered with several sampling modes for
// equal render time each, against a shared long reference, giving error-vs-time curves and
// equal-time relMSE ratios.
//
// How it measures:
// - One RenderView per mode, all with the same scene except render.sampling, the environment
//   hidden (only object pixels carry radiance, so the error is the objects' alone),
//   render.max_samples lifted to the renderer's limit and no target_error (the budget is time),
//   passes of render.samples_per_frame but at most kConvergenceSamplesPerPass samples in all, so
//   a pass stays short and sessions rendering meanwhile are never held up for long.
//   Every mode's shading program is compiled and run once on a small view first, so no mode's
//   time includes the driver's JIT.
// - The reference: one more view in "mis", rendered for reference_ms first.
// - Then the modes' passes are interleaved, the mode with the least render time so far going
//   next, so each gets the same time under the same machine load, until each has time_ms.
// - At kConvergenceCheckpoints checkpoints spaced evenly in log-time from time_ms/64 to time_ms
//   (taken once every mode has reached it), each mode's linear frame is read and compared with
//   the reference:
//     true_rel_error = sqrt(max(0, mean_P (lum(x) - lum(ref))^2 - refVariance)) / mean_P lum(ref)
//   over P, the pixels whose reference luminance is > 0, with lum the Rec. 709 luminance the
//   renderer's rel_error uses and refVariance = rel_error(ref)^2 * (mean_P lum(ref))^2, the
//   reference's own estimated variance per pixel: E[(x - ref)^2] = var(x) + bias(x)^2 +
//   var(ref), so subtracting it leaves the mode's own error. relMSE = true_rel_error^2.
//   Each point also gives raw_rel_error, the same without the subtraction (an upper bound, which
//   does not lean on the reference's own estimate).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "brdfa/renderer.h"
#include "jobs/jobs.h"
#include "json/scene_json.h"

namespace brdfa::server {

inline constexpr int kConvergenceMinMs = 100;
inline constexpr int kConvergenceMaxMs = 60000;            // per mode
inline constexpr int kConvergenceMaxReferenceMs = 240000;  // the reference
inline constexpr int kConvergenceDefaultMs = 2000;
inline constexpr int kConvergenceCheckpoints = 16;
// Largest image a comparison renders (each mode has a view of its own: 48 bytes per pixel and
// G-buffer slice), and the most samples one of its passes takes in all (a short pass on a CPU device).
inline constexpr int kConvergenceMaxPixels = 1024 * 1024;
inline constexpr int kConvergenceSamplesPerPass = 1 << 20;

struct ConvergenceJobSpec {
  Scene scene;  // as given; the job hides the environment and lifts the limits per view
  nlohmann::json sceneJson;
  std::vector<SamplingMode> modes;
  int timeMs = kConvergenceDefaultMs;
  int referenceMs = 4 * kConvergenceDefaultMs;
};

// {"scene": {...}, "modes": [...] (default cosine, brdf, environment, mis), "time_ms",
// "reference_ms" (default 4 x time_ms, at most kConvergenceMaxReferenceMs)}. Errors name the
// field: InvalidArgument (400), or NotFound (404) for unknown names inside the scene.
Result<ConvergenceJobSpec> parseConvergenceJob(const nlohmann::json& body, const SceneResolver& resolver);

// What describe() echoes as "request".
nlohmann::json convergenceJobRequestJson(const ConvergenceJobSpec& spec);

// Runs the comparison above; the result JSON is documented in docs/api.md. Returns early (an
// Error that the job manager drops) when `context` is cancelled.
Result<nlohmann::json> runConvergenceJob(Renderer& renderer, const ConvergenceJobSpec& spec, JobContext& context);

// The formula above for two linear RGBA float images of equal size, given the reference's own
// rel_error. nullopt when no reference pixel has luminance > 0. `meanRefLum`, `pixels` and
// `raw` (optional) receive mean_P lum(ref), |P| and the error without the subtraction.
std::optional<double> trueRelError(const std::vector<float>& rgba, const std::vector<float>& refRgba,
                                   double refRelError, double* meanRefLum = nullptr, size_t* pixels = nullptr,
                                   double* raw = nullptr);

}  // namespace brdfa::server
