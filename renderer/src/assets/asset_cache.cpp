#include "assets/asset_cache.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>

#include "brdfa/measured.h"

#include "assets/environment_preview.h"
#include "assets/environment_sampling.h"
#include "assets/obj_loader.h"
#include "device/vk_check.h"

namespace brdfa {

namespace {

// A device-local buffer holding `bytes`, then `tail` (tailSize bytes) after them.
Result<Buffer> deviceBufferWith(VkContext& ctx, const void* bytes, VkDeviceSize headSize, VkBufferUsageFlags usage,
                                const void* tail = nullptr, VkDeviceSize tailSize = 0) {
  const VkDeviceSize size = headSize + tailSize;
  auto staging = Buffer::create(ctx, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true);
  if (!staging) return staging.takeError();
  std::memcpy(staging->mapped(), bytes, headSize);
  if (tailSize > 0) std::memcpy(static_cast<char*>(staging->mapped()) + headSize, tail, tailSize);
  auto buffer = Buffer::create(ctx, size, usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false);
  if (!buffer) return buffer.takeError();
  auto cmd = CommandContext::create(ctx);
  if (!cmd) return cmd.takeError();
  auto cb = cmd->begin();
  if (!cb) return cb.takeError();
  VkBufferCopy region{0, 0, size};
  vkCmdCopyBuffer(*cb, staging->handle(), buffer->handle(), 1, &region);
  memoryBarrier(*cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_INDEX_READ_BIT | VK_ACCESS_SHADER_READ_BIT);
  BRDFA_TRY(cmd->submitAndWait());
  return buffer;
}

// Reads `size` bytes (the file's size, as reserved) into one string: no second copy.
Result<std::string> readWholeFile(const std::string& path, uint64_t size) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(ErrorCode::NotFound, "asset file is missing: " + path);
  std::string bytes(size, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  if (static_cast<uint64_t>(in.gcount()) != size)
    return makeError(ErrorCode::Internal, "cannot read asset file " + path);
  return bytes;
}

// A registered asset's file failed to decode although it passed inspectAsset when stored
// (edited or damaged on disk): a scene error naming the asset, not a crash.
Error assetError(Error e, AssetKind kind, const std::string& name) {
  e.message = std::string(assetKindName(kind)) + " '" + name + "': " + e.message;
  return e;
}

// Stored assets passed inspectAsset, with the configured limits, when they were stored: read
// back, they are decoded without limits.
constexpr AssetLimits kUnlimited{~0ull, ~0ull, ~0ull};

// Looks `name` up in a cache of weak references, dropping the entry when it has expired.
template <class T>
std::shared_ptr<const T> lockCached(std::map<std::string, std::weak_ptr<const T>>& cache, const std::string& name) {
  auto it = cache.find(name);
  if (it == cache.end()) return nullptr;
  auto strong = it->second.lock();
  if (!strong) cache.erase(it);
  return strong;
}

// What an asset's data holds on the host (decoded), and what its upload makes on the device:
// the budget's figures for them (upper bounds where the device form is chosen at upload).
uint64_t hostBytes(const MeshData& m) { return m.vertices.size() * sizeof(Vertex) + m.indices.size() * 4; }
uint64_t deviceBytes(const MeshData& m) { return hostBytes(m); }
uint64_t hostBytes(const TextureData& t) { return t.rgba8.size(); }
uint64_t deviceBytes(const TextureData& t) { return uint64_t(t.width) * t.height * 4; }
// The device copy carries the sampling proposal after the table (measured_merl.glsl).
constexpr size_t kMeasuredTailFloats = 4;
uint64_t hostBytes(const MeasuredTable& t) { return t.bytes(); }
uint64_t deviceBytes(const MeasuredTable& t) { return t.bytes() + kMeasuredTailFloats * sizeof(float); }
uint64_t hostBytes(const EnvironmentData& e) { return e.texels.size() * sizeof(float); }
uint64_t deviceBytes(const EnvironmentData& e) {
  const uint64_t cube = uint64_t(e.faceSize) * e.faceSize * 6 * 4 * sizeof(uint16_t);  // RGBA16F
  // The sampling table, on the device and again on the host (EnvironmentDistribution).
  const uint64_t table = e.constant ? 0 : (2 * (6ull * kMaxCellsPerEdge * kMaxCellsPerEdge + 1) + kPreviewEntries) * 8;
  return cube + table;
}

template <class Gpu>
void dropUnusedAssets(std::map<std::string, std::shared_ptr<const Gpu>>& cache, uint64_t needed, uint64_t& freed,
                      std::vector<std::string>& names) {
  for (auto it = cache.begin(); it != cache.end() && freed < needed;) {
    if (it->second.use_count() == 1) {
      freed += it->second->memory.bytes();
      names.push_back(it->second->name);
      it = cache.erase(it);
    } else {
      ++it;
    }
  }
}

std::vector<std::string> withRegistered(std::vector<std::string> names,
                                        const std::map<std::pair<AssetKind, std::string>, std::string>& registered,
                                        AssetKind kind) {
  for (const auto& [key, path] : registered)  // sorted by (kind, name)
    if (key.first == kind) names.push_back(key.second);
  return names;
}
}  // namespace

AssetCache::AssetCache(VkContext& ctx, MemoryLedger& ledger, CacheShrinker shrinker)
    : ctx_(ctx), ledger_(ledger), shrinker_(std::move(shrinker)) {}

AssetCache::~AssetCache() {
  pinnedMeasured_.clear();
  environments_.clear();
  meshes_.clear();
  textures_.clear();
  if (envSampler_) vkDestroySampler(ctx_.device(), envSampler_, nullptr);
  if (textureSampler_) vkDestroySampler(ctx_.device(), textureSampler_, nullptr);
}

Result<void> AssetCache::init() {
  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = VK_FILTER_LINEAR;
  sci.minFilter = VK_FILTER_LINEAR;
  sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  sci.maxLod = 0.0f;
  BRDFA_VK_TRY(vkCreateSampler(ctx_.device(), &sci, nullptr, &envSampler_));

  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  BRDFA_VK_TRY(vkCreateSampler(ctx_.device(), &sci, nullptr, &textureSampler_));

  ImageSpec white;
  white.format = VK_FORMAT_R8G8B8A8_UNORM;
  white.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  auto image = Image::create(ctx_, white);
  if (!image) return image.takeError();
  whiteTexture_ = std::move(image.value());
  const uint32_t texel = 0xffffffffu;
  BRDFA_TRY(uploadImage(ctx_, whiteTexture_, &texel, sizeof texel));

  // Far shorter than a table: a measured program bound to it reads nothing (measured_merl.glsl).
  const float none[4] = {-1, -1, -1, -1};
  auto table = deviceBufferWith(ctx_, none, sizeof none, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!table) return table.takeError();
  noMeasuredTable_ = std::move(table.value());
  return {};
}

Result<void> AssetCache::registerAsset(const std::string& name, AssetKind kind, const std::string& path) {
  if (name.empty()) return makeError(ErrorCode::InvalidArgument, "an asset needs a name");
  std::vector<std::string> builtins = kind == AssetKind::Mesh          ? builtinMeshNames()
                                      : kind == AssetKind::Texture     ? builtinTextureNames()
                                      : kind == AssetKind::Environment ? builtinEnvironmentNames()
                                                                       : std::vector<std::string>{};
  if (std::find(builtins.begin(), builtins.end(), name) != builtins.end())
    return makeError(ErrorCode::InvalidArgument, "'" + name + "' is a built-in " + assetKindName(kind) + " name");
  {
    std::lock_guard<std::mutex> lock(assetMutex_);
    registered_[{kind, name}] = path;
    // Later scenes load the new file; views already holding the old one keep it.
    if (kind == AssetKind::Mesh) uploadedMeshes_.erase(name);
    if (kind == AssetKind::Environment) uploadedEnvironments_.erase(name);
    if (kind == AssetKind::Texture) {
      uploadedTextures_.erase(name + "|srgb");
      uploadedTextures_.erase(name + "|linear");
    }
    if (kind == AssetKind::Measured) {
      uploadedMeasured_.erase(name);
      pinnedMeasured_.erase(name);
    }
  }
  if (kind != AssetKind::Measured) return {};
  // A measured table is loaded now and kept: its memory is taken when it is registered, so a
  // table the budget cannot hold is refused at its upload (OverBudget), not in a later scene.
  auto table = measured(name);
  std::lock_guard<std::mutex> lock(assetMutex_);
  if (!table) {
    registered_.erase({kind, name});
    return table.takeError();
  }
  pinnedMeasured_[name] = table.value();
  return {};
}

Result<std::string> AssetCache::registeredPath(AssetKind kind, const std::string& name) const {
  auto it = registered_.find({kind, name});
  if (it == registered_.end())
    return makeError(ErrorCode::NotFound, std::string("unknown ") + assetKindName(kind) + " '" + name + "'");
  return it->second;
}

template <class Gpu, class MakeBuiltin, class Decode, class Upload>
Result<std::shared_ptr<const Gpu>> AssetCache::findOrLoad(AssetKind kind, const std::string& name,
                                                          const std::string& key,
                                                          std::map<std::string, std::shared_ptr<const Gpu>>& builtins,
                                                          std::map<std::string, std::weak_ptr<const Gpu>>& uploads,
                                                          MakeBuiltin makeBuiltin, Decode decode, Upload upload) {
  if (auto it = builtins.find(key); it != builtins.end()) return it->second;
  if (auto cached = lockCached(uploads, key)) return cached;
  const std::string what = std::string("the ") + assetKindName(kind) + " '" + name + "'";
  // Reserves what the asset will hold on the device, and for the upload's length its decoded
  // data and staging buffers, then uploads it.
  auto place = [&](const auto& data) -> Result<std::shared_ptr<Gpu>> {
    const uint64_t resident = deviceBytes(data);
    BRDFA_TRY(ledger_.reserve(MemoryUse::Transfers, hostBytes(data) + resident, what, shrinker_({.assets = true})));
    MemoryReservation transfer(&ledger_, MemoryUse::Transfers, hostBytes(data) + resident);
    BRDFA_TRY(ledger_.reserve(MemoryUse::Assets, resident, what, shrinker_({.assets = true})));
    MemoryReservation memory(&ledger_, MemoryUse::Assets, resident);
    auto gpu = upload(data);
    if (!gpu) return gpu.takeError();
    (*gpu)->memory = std::move(memory);
    return gpu;
  };
  if (auto builtin = makeBuiltin()) {
    auto gpu = place(*builtin);
    if (!gpu) return gpu.takeError();
    builtins[key] = gpu.value();
    return std::shared_ptr<const Gpu>(gpu.value());
  }
  auto path = registeredPath(kind, name);
  if (!path) return path.takeError();
  // The file and what it decodes to are in flight until the upload ends: reserved before the
  // file is read, so a file the budget cannot hold is refused before it takes the memory.
  std::error_code ec;
  const uint64_t fileBytes = std::filesystem::file_size(*path, ec);
  if (ec) return assetError(makeError(ErrorCode::NotFound, "asset file is missing: " + *path), kind, name);
  BRDFA_TRY(ledger_.reserve(MemoryUse::Transfers, fileBytes, what, shrinker_({.assets = true})));
  MemoryReservation file(&ledger_, MemoryUse::Transfers, fileBytes);
  auto bytes = readWholeFile(*path, fileBytes);
  if (!bytes) return assetError(bytes.takeError(), kind, name);
  auto data = decode(std::string_view(*bytes));
  if (!data) return assetError(data.takeError(), kind, name);
  auto gpu = place(*data);
  if (!gpu) return gpu.takeError();
  uploads[key] = gpu.value();
  return std::shared_ptr<const Gpu>(gpu.value());
}

Result<std::shared_ptr<GpuEnvironment>> AssetCache::uploadEnvironment(const std::string& name,
                                                                      const EnvironmentData& data) {
  ImageSpec spec;
  spec.width = spec.height = data.faceSize;
  spec.layers = 6;
  spec.cube = true;
  spec.format = VK_FORMAT_R16G16B16A16_SFLOAT;  // linear filtering is guaranteed for 16F, not 32F
  spec.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  auto image = Image::create(ctx_, spec);
  if (!image) return image.takeError();
  const HalfCube half = packHalfCube(data);
  BRDFA_TRY(uploadImage(ctx_, *image, half.texels.data(), half.texels.size() * sizeof(uint16_t)));
  std::shared_ptr<const EnvironmentDistribution> distribution;
  if (!data.constant) {
    // The table is a texel buffer, and Vulkan only promises 65536 texels in one: a device at that
    // minimum gets coarser cells (6 D^2 + 1 entries and the preview's must fit).
    uint32_t maxCells = kMaxCellsPerEdge;
    while (maxCells > 1 && 6ull * maxCells * maxCells + 1 + kPreviewEntries > ctx_.limits().maxTexelBufferElements)
      maxCells /= 2;
    distribution = std::make_shared<const EnvironmentDistribution>(buildEnvironmentDistribution(data, maxCells));
  }
  std::vector<uint32_t> table = distribution ? distribution->table : EnvironmentDistribution::constantHeader();
  if (distribution) {  // the preview kernel's coarse radiance after the cells (environment_preview.h)
    const std::vector<uint32_t> preview = previewRadianceEntries(data, half.scale);
    table.insert(table.end(), preview.begin(), preview.end());
  }
  auto tableBuffer = TexelBuffer::create(ctx_, table.data(), table.size() * sizeof(uint32_t), VK_FORMAT_R32G32_UINT);
  if (!tableBuffer) return tableBuffer.takeError();
  auto env = std::make_shared<GpuEnvironment>();
  env->name = name;
  env->constant = data.constant;
  env->scale = half.scale;
  env->cube = std::move(image.value());
  env->table = std::move(tableBuffer.value());
  env->distribution = std::move(distribution);
  return env;
}

Result<std::shared_ptr<const GpuEnvironment>> AssetCache::environment(const std::string& name) {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return findOrLoad(
      AssetKind::Environment, name, name, environments_, uploadedEnvironments_,
      [&] { return makeBuiltinEnvironment(name); },
      [&](std::string_view bytes) { return decodeEnvironment(bytes, kUnlimited, name, nullptr); },
      [&](const EnvironmentData& data) { return uploadEnvironment(name, data); });
}

Result<std::shared_ptr<GpuMesh>> AssetCache::uploadMesh(const std::string& name, const MeshData& data) {
  if (data.vertices.empty() || data.indices.empty())
    return makeError(ErrorCode::InvalidArgument, "mesh '" + name + "' has no triangles");
  auto gpu = std::make_shared<GpuMesh>();
  gpu->name = name;
  gpu->vertexCount = static_cast<uint32_t>(data.vertices.size());
  for (int a = 0; a < 3; ++a) {
    gpu->boundsMin[a] = INFINITY;
    gpu->boundsMax[a] = -INFINITY;
  }
  for (const Vertex& v : data.vertices)
    for (int a = 0; a < 3; ++a) {
      gpu->boundsMin[a] = std::min(gpu->boundsMin[a], v.position[a]);
      gpu->boundsMax[a] = std::max(gpu->boundsMax[a], v.position[a]);
    }
  gpu->indexCount = static_cast<uint32_t>(data.indices.size());
  auto vb = deviceBufferWith(ctx_, data.vertices.data(), data.vertices.size() * sizeof(Vertex),
                             VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  if (!vb) return vb.takeError();
  auto ib = deviceBufferWith(ctx_, data.indices.data(), data.indices.size() * sizeof(uint32_t),
                             VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
  if (!ib) return ib.takeError();
  gpu->vertices = std::move(vb.value());
  gpu->indices = std::move(ib.value());
  return gpu;
}

Result<std::shared_ptr<const GpuMesh>> AssetCache::mesh(const std::string& name) {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return findOrLoad(
      AssetKind::Mesh, name, name, meshes_, uploadedMeshes_, [&] { return makeBuiltinMesh(name); },
      [&](std::string_view bytes) { return loadObjMesh(bytes, kUnlimited, nullptr); },
      [&](const MeshData& data) { return uploadMesh(name, data); });
}

Result<std::shared_ptr<GpuTexture>> AssetCache::uploadTexture(const std::string& name, bool srgb,
                                                              const TextureData& data) {
  if (data.width == 0 || data.height == 0 || data.rgba8.size() != size_t(data.width) * data.height * 4)
    return makeError(ErrorCode::InvalidArgument, "texture '" + name + "' has no pixels");
  ImageSpec spec;
  spec.width = data.width;
  spec.height = data.height;
  // The sampler decodes sRGB to linear (before filtering, as it should be).
  spec.format = srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM;
  spec.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  auto image = Image::create(ctx_, spec);
  if (!image) return image.takeError();
  BRDFA_TRY(uploadImage(ctx_, *image, data.rgba8.data(), data.rgba8.size()));
  auto texture = std::make_shared<GpuTexture>();
  texture->name = name;
  texture->srgb = srgb;
  texture->image = std::move(image.value());
  return texture;
}

Result<std::shared_ptr<const GpuTexture>> AssetCache::texture(const std::string& name, bool srgb) {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return findOrLoad(
      AssetKind::Texture, name, name + (srgb ? "|srgb" : "|linear"), textures_, uploadedTextures_,
      [&] { return makeBuiltinTexture(name); },
      [&](std::string_view bytes) { return decodeTexture(bytes, kUnlimited); },
      [&](const TextureData& data) { return uploadTexture(name, srgb, data); });
}

Result<std::shared_ptr<GpuMeasured>> AssetCache::uploadMeasured(const std::string& name, const MeasuredTable& data) {
  const float tail[kMeasuredTailFloats] = {data.lobeAlpha, data.lobeWeight, 0.0f, 0.0f};
  auto buffer =
      deviceBufferWith(ctx_, data.rgb.data(), data.bytes(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, tail, sizeof tail);
  if (!buffer) return buffer.takeError();
  auto gpu = std::make_shared<GpuMeasured>();
  gpu->name = name;
  gpu->table = std::move(buffer.value());
  return gpu;
}

Result<std::shared_ptr<const GpuMeasured>> AssetCache::measured(const std::string& name) {
  std::lock_guard<std::mutex> lock(assetMutex_);
  std::map<std::string, std::shared_ptr<const GpuMeasured>> noBuiltins;
  return findOrLoad(
      AssetKind::Measured, name, name, noBuiltins, uploadedMeasured_, [] { return std::optional<MeasuredTable>(); },
      [](std::string_view bytes) { return readMerl(bytes); },
      [&](const MeasuredTable& data) { return uploadMeasured(name, data); });
}

void AssetCache::writeMeasured(VkDescriptorSet objectSet, const GpuMeasured* table) const {
  VkDescriptorBufferInfo info{table ? table->table.handle() : noMeasuredTable_.handle(), 0, VK_WHOLE_SIZE};
  VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, objectSet, 6,      0, 1,
                         VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,      nullptr, &info,     nullptr};
  vkUpdateDescriptorSets(ctx_.device(), 1, &w, 0, nullptr);
}

std::vector<std::string> AssetCache::environmentNames() const {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return withRegistered(builtinEnvironmentNames(), registered_, AssetKind::Environment);
}

std::vector<std::string> AssetCache::meshNames() const {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return withRegistered(builtinMeshNames(), registered_, AssetKind::Mesh);
}

std::vector<std::string> AssetCache::textureNames() const {
  std::lock_guard<std::mutex> lock(assetMutex_);
  return withRegistered(builtinTextureNames(), registered_, AssetKind::Texture);
}

void AssetCache::writeTextures(VkDescriptorSet objectSet,
                               const std::shared_ptr<const GpuTexture> (&textures)[kMaxTextures]) const {
  std::array<VkDescriptorImageInfo, kMaxTextures> info{};
  std::array<VkWriteDescriptorSet, kMaxTextures> w{};
  for (uint32_t i = 0; i < kMaxTextures; ++i) {
    info[i] = {textureSampler_, textures[i] ? textures[i]->image.view() : whiteTexture_.view(),
               VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    w[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,    nullptr,  objectSet, 2 + i,  0, 1,
            VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, &info[i], nullptr,   nullptr};
  }
  vkUpdateDescriptorSets(ctx_.device(), static_cast<uint32_t>(w.size()), w.data(), 0, nullptr);
}

void AssetCache::writeDefaultTextures(VkDescriptorSet objectSet) const {
  const std::shared_ptr<const GpuTexture> none[kMaxTextures];
  writeTextures(objectSet, none);
}

void AssetCache::dropUnused(uint64_t needed, bool assetLockHeld, uint64_t& freed, std::vector<std::string>& names) {
  underFreeLock(assetMutex_, assetLockHeld, [&] {
    dropUnusedAssets(environments_, needed, freed, names);
    dropUnusedAssets(meshes_, needed, freed, names);
    dropUnusedAssets(textures_, needed, freed, names);
  });
}

}  // namespace brdfa
