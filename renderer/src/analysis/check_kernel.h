// What the device checks and analyses of analysis/ run on: a check kernel (shaders/kernels/)
// specialized to a BRDF, dispatched once per parameter setting, its output read back.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "brdfa/brdf.h"
#include "brdfa/result.h"

#include "assets/asset_cache.h"
#include "assets/gpu_assets.h"
#include "device/vk_context.h"
#include "programs/pipeline_layouts.h"
#include "programs/program_cache.h"

namespace brdfa::analysis {

// The renderer's parts a check kernel needs; all outlive the call.
struct CheckDevice {
  VkContext& ctx;
  const PipelineLayouts& layouts;
  ProgramCache& programs;
  AssetCache& assets;  // the furnace environment, the environment sampler, the white texture
};

// Runs a check kernel once per entry of `settings` over `invocations` invocations with an
// output of `outputVec4s` vec4; `consume` reads the output after each run. `input` (when not
// empty) is bound read-only at set 0 binding 0; `env` (default: the furnace) is the environment.
// Legacy render() files are Unsupported.
Result<void> runCheckKernel(const CheckDevice& device, const BrdfDefinition& brdf, const char* kernelName,
                            uint32_t invocations, uint32_t outputVec4s,
                            const std::vector<std::map<std::string, Vec3>>& settings,
                            const std::function<void(const float*)>& consume, const std::vector<float>& input = {},
                            const GpuEnvironment* env = nullptr);

}  // namespace brdfa::analysis
