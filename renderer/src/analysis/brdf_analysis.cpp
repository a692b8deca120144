// Renderer::evaluateBrdf and Renderer::estimateAlbedo (renderer.h): the device side of the
// analysis plots, through shaders/kernels/analysis.comp.glsl.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "analysis/check_kernel.h"
#include "analysis/device_checks.h"

namespace brdfa {

namespace {

constexpr uint32_t kChunkSamples = 1024;  // samples per albedo replicate
constexpr uint32_t kMaxPairs = 1u << 16;  // pairs per evaluateBrdf call
constexpr uint32_t kMaxReplicates = 256;  // per view
// Albedo evaluations per submission: each submission of an analysis runs under the pass budget
// (RendererOptions::passSeconds) and holds the shared queue meanwhile, so they stay short.
constexpr uint64_t kSubmissionSamples = 1u << 18;

std::vector<float> header(uint32_t mode, uint32_t items, uint32_t perChunk, uint32_t chunks) {
  std::vector<float> input(4);
  const uint32_t words[4] = {mode, items, perChunk, chunks};
  std::memcpy(input.data(), words, sizeof words);
  return input;
}

void append(std::vector<float>& input, const Vec3& v) { input.insert(input.end(), {v[0], v[1], v[2], 0.0f}); }

}  // namespace

const char* albedoEstimatorName(const BrdfDefinition& brdf) {
  return brdf.hasSampler() ? "brdf sampler" : "cosine + half-vector mixture";
}

namespace analysis {

Result<std::vector<Vec3>> evaluateBrdf(const CheckDevice& device, const BrdfDefinition& brdf,
                                       const std::vector<ParamSetting>& settings,
                                       const std::vector<DirectionPair>& pairs) {
  if (pairs.empty() || settings.empty()) return std::vector<Vec3>{};
  if (pairs.size() > kMaxPairs)
    return makeError(ErrorCode::InvalidArgument, "at most " + std::to_string(kMaxPairs) + " direction pairs per call");
  const uint32_t n = static_cast<uint32_t>(pairs.size());
  std::vector<float> input = header(0, n, 0, 0);
  for (const DirectionPair& p : pairs) {
    append(input, p.light);
    append(input, p.view);
  }
  std::vector<Vec3> values;
  values.reserve(size_t(n) * settings.size());
  auto ran = runCheckKernel(
      device, brdf, "analysis.comp.glsl", n, n, settings,
      [&](const float* out) {
        for (uint32_t p = 0; p < n; ++p) values.push_back({out[4 * p], out[4 * p + 1], out[4 * p + 2]});
      },
      input);
  if (!ran) return ran.takeError();
  return values;
}

Result<std::vector<AlbedoEstimate>> estimateAlbedo(const CheckDevice& device, const BrdfDefinition& brdf,
                                                   const std::vector<ParamSetting>& settings,
                                                   const std::vector<Vec3>& views, uint32_t samplesPerView) {
  if (views.empty() || settings.empty()) return std::vector<AlbedoEstimate>{};
  // Two replicates at least: their spread is the error bar.
  const uint32_t chunks = std::clamp<uint32_t>((samplesPerView + kChunkSamples - 1) / kChunkSamples, 2, kMaxReplicates);
  const uint32_t viewsPerCall =
      static_cast<uint32_t>(std::max<uint64_t>(1, kSubmissionSamples / (uint64_t(chunks) * kChunkSamples)));
  std::vector<AlbedoEstimate> out(settings.size() * views.size());
  for (size_t first = 0; first < views.size(); first += viewsPerCall) {
    const uint32_t count = static_cast<uint32_t>(std::min<size_t>(viewsPerCall, views.size() - first));
    std::vector<float> input = header(1, count, kChunkSamples, chunks);
    for (uint32_t v = 0; v < count; ++v) append(input, views[first + v]);
    size_t setting = 0;
    auto ran = runCheckKernel(
        device, brdf, "analysis.comp.glsl", count * chunks, count * chunks, settings,
        [&](const float* o) {
          for (uint32_t v = 0; v < count; ++v) {
            double sum[3] = {0, 0, 0}, sumSq[3] = {0, 0, 0};
            AlbedoEstimate& e = out[setting * views.size() + first + v];
            for (uint32_t c = 0; c < chunks; ++c) {
              const float* r = o + 4 * size_t(v * chunks + c);
              for (int k = 0; k < 3; ++k) {
                const double m = double(r[k]) / kChunkSamples;
                sum[k] += m;
                sumSq[k] += m * m;
              }
              e.nonFinite += static_cast<uint64_t>(r[3]);
            }
            for (int k = 0; k < 3; ++k) {
              const double mean = sum[k] / chunks;
              const double var = std::max(sumSq[k] / chunks - mean * mean, 0.0) * chunks / (chunks - 1.0);
              e.mean[k] = float(mean);
              e.stdError[k] = float(std::sqrt(var / chunks));
            }
            e.samples = uint64_t(chunks) * kChunkSamples;
          }
          ++setting;
        },
        input);
    if (!ran) return ran.takeError();
  }
  return out;
}

}  // namespace analysis

}  // namespace brdfa
