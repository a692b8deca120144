#include "minimal_kernel.h"

#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>

#include "assets/environment_maps.h"
#include "device/vk_check.h"
#include "device/vk_context.h"
#include "device/vk_resources.h"
#include "programs/glsl_compiler.h"

namespace brdfa::bench {

int spherePixels(int width, int height) {
  const float t = std::tan(45.0f * 3.14159265f / 360.0f);
  int n = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      float nx = (2.0f * (x + 0.5f) / width - 1.0f) * t * width / height;
      float ny = (1.0f - 2.0f * (y + 0.5f) / height) * t;
      float len = std::sqrt(nx * nx + ny * ny + 1.0f);
      float dz = -1.0f / len;  // dir = (nx, ny, -1) / len, origin (0, 0, 3)
      float b = 3.0f * dz, c = 9.0f - 1.0f;
      if (b * b - c >= 0.0f) ++n;
    }
  return n;
}

namespace {
struct Push {
  uint32_t width, height, firstSample, count;
  float tanHalfFov;
};
}  // namespace

struct MinimalKernel::State {
  std::unique_ptr<VkContext> ctx;
  Image cube;
  Buffer accum;
  CommandContext cmd;
  VkSampler sampler = VK_NULL_HANDLE;
  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkPipeline pipeline = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VkDescriptorSet set = VK_NULL_HANDLE;
  int width = 0, height = 0;
  uint32_t nextSample = 0;

  ~State() {
    if (!ctx) return;
    VkDevice d = ctx->device();
    vkDeviceWaitIdle(d);
    cmd.reset();
    if (pool) vkDestroyDescriptorPool(d, pool, nullptr);
    if (pipeline) vkDestroyPipeline(d, pipeline, nullptr);
    if (layout) vkDestroyPipelineLayout(d, layout, nullptr);
    if (setLayout) vkDestroyDescriptorSetLayout(d, setLayout, nullptr);
    if (sampler) vkDestroySampler(d, sampler, nullptr);
    cube.reset();
    accum.reset();
  }
};

MinimalKernel::MinimalKernel(std::unique_ptr<State> s) : s_(std::move(s)) {}
MinimalKernel::~MinimalKernel() = default;

Result<std::unique_ptr<MinimalKernel>> MinimalKernel::create(const std::string& sourceDir, int width, int height) {
  auto st = std::make_unique<State>();
  st->width = width;
  st->height = height;
  auto ctx = VkContext::create(RendererOptions{});
  if (!ctx) return ctx.takeError();
  st->ctx = std::move(ctx.value());
  VkContext& c = *st->ctx;
  VkDevice d = c.device();

  std::ifstream in(sourceDir + "/bench/minimal_kernel.glsl");
  std::stringstream text;
  text << in.rdbuf();
  auto spirv = compileGlsl(ShaderStage::Compute, text.str());
  if (!spirv) return spirv.takeError();

  auto env = makeBuiltinEnvironment("sky");
  if (!env) return env.takeError();
  ImageSpec spec;
  spec.width = spec.height = env->faceSize;
  spec.layers = 6;
  spec.cube = true;
  spec.format = VK_FORMAT_R16G16B16A16_SFLOAT;
  spec.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  auto cube = Image::create(c, spec);
  if (!cube) return cube.takeError();
  st->cube = std::move(cube.value());
  const HalfCube half = packHalfCube(*env);  // the sky fits the half range: scale 1
  BRDFA_TRY(uploadImage(c, st->cube, half.texels.data(), half.texels.size() * sizeof(uint16_t)));
  auto accum = Buffer::create(c, VkDeviceSize(width) * height * 16,
                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false);
  if (!accum) return accum.takeError();
  st->accum = std::move(accum.value());

  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = sci.minFilter = VK_FILTER_LINEAR;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  BRDFA_VK_TRY(vkCreateSampler(d, &sci, nullptr, &st->sampler));
  VkDescriptorSetLayoutBinding bindings[2] = {
      {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr}};
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = 2;
  lci.pBindings = bindings;
  BRDFA_VK_TRY(vkCreateDescriptorSetLayout(d, &lci, nullptr, &st->setLayout));
  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(Push)};
  VkPipelineLayoutCreateInfo plci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  plci.setLayoutCount = 1;
  plci.pSetLayouts = &st->setLayout;
  plci.pushConstantRangeCount = 1;
  plci.pPushConstantRanges = &range;
  BRDFA_VK_TRY(vkCreatePipelineLayout(d, &plci, nullptr, &st->layout));
  VkShaderModuleCreateInfo mci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  mci.codeSize = spirv->words.size() * 4;
  mci.pCode = spirv->words.data();
  VkShaderModule module;
  BRDFA_VK_TRY(vkCreateShaderModule(d, &mci, nullptr, &module));
  VkComputePipelineCreateInfo cpi{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  cpi.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
               nullptr,
               0,
               VK_SHADER_STAGE_COMPUTE_BIT,
               module,
               "main",
               nullptr};
  cpi.layout = st->layout;
  VkResult r = vkCreateComputePipelines(d, VK_NULL_HANDLE, 1, &cpi, nullptr, &st->pipeline);
  vkDestroyShaderModule(d, module, nullptr);
  if (r != VK_SUCCESS) return vkError(r, "vkCreateComputePipelines");
  VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1},
                                   {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1}};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.maxSets = 1;
  pci.poolSizeCount = 2;
  pci.pPoolSizes = sizes;
  BRDFA_VK_TRY(vkCreateDescriptorPool(d, &pci, nullptr, &st->pool));
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = st->pool;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &st->setLayout;
  BRDFA_VK_TRY(vkAllocateDescriptorSets(d, &ai, &st->set));
  VkDescriptorBufferInfo bi{st->accum.handle(), 0, VK_WHOLE_SIZE};
  VkDescriptorImageInfo ii{st->sampler, st->cube.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  VkWriteDescriptorSet w[2] = {};
  w[0] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, st->set, 0,      0, 1,
          VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,      nullptr, &bi,     nullptr};
  w[1] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,    nullptr, st->set, 1,      0, 1,
          VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, &ii,     nullptr, nullptr};
  vkUpdateDescriptorSets(d, 2, w, 0, nullptr);
  auto cmd = CommandContext::create(c);
  if (!cmd) return cmd.takeError();
  st->cmd = std::move(cmd.value());
  return std::unique_ptr<MinimalKernel>(new MinimalKernel(std::move(st)));
}

Result<double> MinimalKernel::pass(int samples) {
  State& st = *s_;
  auto t0 = std::chrono::steady_clock::now();
  auto cb = st.cmd.begin();
  if (!cb) return cb.takeError();
  Push push{uint32_t(st.width), uint32_t(st.height), st.nextSample, uint32_t(samples),
            std::tan(45.0f * 3.14159265f / 360.0f)};
  st.nextSample += uint32_t(samples);
  vkCmdBindPipeline(*cb, VK_PIPELINE_BIND_POINT_COMPUTE, st.pipeline);
  vkCmdBindDescriptorSets(*cb, VK_PIPELINE_BIND_POINT_COMPUTE, st.layout, 0, 1, &st.set, 0, nullptr);
  vkCmdPushConstants(*cb, st.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
  vkCmdDispatch(*cb, (st.width + 7) / 8, (st.height + 7) / 8, 1);
  BRDFA_TRY(st.cmd.submitAndWait());
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace brdfa::bench
