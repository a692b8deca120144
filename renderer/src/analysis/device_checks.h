// The renderer's device checks and analyses of BRDFs and environments, as Renderer::checkBrdf,
// checkSampler, checkEnvironmentSampler, evaluateBrdf and estimateAlbedo promise them
// (renderer.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "brdfa/brdf.h"
#include "brdfa/renderer.h"
#include "brdfa/result.h"

#include "analysis/check_kernel.h"

namespace brdfa::analysis {

Result<BrdfCheckReport> checkBrdf(const CheckDevice& device, const BrdfDefinition& brdf);
Result<SamplerCheckReport> checkSampler(const CheckDevice& device, const BrdfDefinition& brdf);
Result<EnvironmentSamplerReport> checkEnvironmentSampler(const CheckDevice& device, const std::string& environment);
Result<std::vector<Vec3>> evaluateBrdf(const CheckDevice& device, const BrdfDefinition& brdf,
                                       const std::vector<ParamSetting>& settings,
                                       const std::vector<DirectionPair>& pairs);
Result<std::vector<AlbedoEstimate>> estimateAlbedo(const CheckDevice& device, const BrdfDefinition& brdf,
                                                   const std::vector<ParamSetting>& settings,
                                                   const std::vector<Vec3>& views, uint32_t samplesPerView);

}  // namespace brdfa::analysis
