// The renderer's assets on the device: environments, meshes and textures by name, each loaded
// once (a built-in, or a registered file) and shared between views, and the samplers and the
// default texture that bind them.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "brdfa/assets.h"
#include "brdfa/measured.h"
#include "brdfa/renderer.h"

#include "assets/environment_maps.h"
#include "assets/gpu_assets.h"
#include "assets/image_decode.h"
#include "assets/meshes.h"
#include "core/memory_ledger.h"
#include "device/vk_context.h"
#include "device/vk_resources.h"

namespace brdfa {

class AssetCache {
 public:
  // `ctx` and `ledger` outlive the cache; `shrinker` makes room in the memory budget when an
  // asset does not fit.
  AssetCache(VkContext& ctx, MemoryLedger& ledger, CacheShrinker shrinker);
  ~AssetCache();
  AssetCache(const AssetCache&) = delete;
  AssetCache& operator=(const AssetCache&) = delete;
  // Creates the samplers and the default texture.
  Result<void> init();

  // Renderer::registerAsset and the name lists (renderer.h).
  Result<void> registerAsset(const std::string& name, AssetKind kind, const std::string& path);
  std::vector<std::string> environmentNames() const;
  std::vector<std::string> meshNames() const;
  std::vector<std::string> textureNames() const;

  // Built-ins are kept for the cache's life; registered (uploaded) assets only while a view
  // holds them, so large uploads do not pile up in memory.
  Result<std::shared_ptr<const GpuEnvironment>> environment(const std::string& name);
  Result<std::shared_ptr<const GpuMesh>> mesh(const std::string& name);
  Result<std::shared_ptr<const GpuTexture>> texture(const std::string& name, bool srgb);
  // A registered measured table (kept from its registration until it is registered again).
  Result<std::shared_ptr<const GpuMeasured>> measured(const std::string& name);

  VkSampler environmentSampler() const { return envSampler_; }
  // Binds `textures` (null entries: white) to set 1 bindings 2..5 of `objectSet`.
  void writeTextures(VkDescriptorSet objectSet,
                     const std::shared_ptr<const GpuTexture> (&textures)[kMaxTextures]) const;
  // Binds the 1x1 white texture to the four texture slots (set 1, bindings 2..5) of `objectSet`:
  // every slot of a bound set must hold a valid image (see analysis/check_kernel.cpp).
  void writeDefaultTextures(VkDescriptorSet objectSet) const;
  // Binds `table` (null: a stand-in shorter than any table) to set 1 binding 6 of `objectSet`;
  // every object set gets one, measured or not.
  void writeMeasured(VkDescriptorSet objectSet, const GpuMeasured* table) const;

  // Part of the memory budget's shrink: drops built-in assets that nothing but the cache holds
  // until `freed` reaches `needed`, adding their names to `names`. The asset lock is taken only
  // if free unless `assetLockHeld`.
  void dropUnused(uint64_t needed, bool assetLockHeld, uint64_t& freed, std::vector<std::string>& names);

 private:
  Result<std::string> registeredPath(AssetKind kind, const std::string& name) const;  // assetMutex_ held
  // The lookup every asset kind shares (assetMutex_ held): `key` in the built-ins' cache, then in
  // the uploads' cache; else a built-in made now by `makeBuiltin()`, else the file registered as
  // (kind, name), read and `decode`d. `upload(data)` puts what was made on the device.
  template <class Gpu, class MakeBuiltin, class Decode, class Upload>
  Result<std::shared_ptr<const Gpu>> findOrLoad(AssetKind kind, const std::string& name, const std::string& key,
                                                std::map<std::string, std::shared_ptr<const Gpu>>& builtins,
                                                std::map<std::string, std::weak_ptr<const Gpu>>& uploads,
                                                MakeBuiltin makeBuiltin, Decode decode, Upload upload);
  Result<std::shared_ptr<GpuMesh>> uploadMesh(const std::string& name, const MeshData& data);
  Result<std::shared_ptr<GpuEnvironment>> uploadEnvironment(const std::string& name, const EnvironmentData& data);
  Result<std::shared_ptr<GpuTexture>> uploadTexture(const std::string& name, bool srgb, const TextureData& data);
  Result<std::shared_ptr<GpuMeasured>> uploadMeasured(const std::string& name, const MeasuredTable& data);

  VkContext& ctx_;
  MemoryLedger& ledger_;
  CacheShrinker shrinker_;
  VkSampler envSampler_ = VK_NULL_HANDLE;
  VkSampler textureSampler_ = VK_NULL_HANDLE;  // iTexture0..3: linear, repeating
  Image whiteTexture_;                         // 1x1 RGBA8 (1, 1, 1, 1): an unbound texture slot
  Buffer noMeasuredTable_;                     // binding 6 of an object that is not measured

  mutable std::mutex assetMutex_;
  std::map<std::pair<AssetKind, std::string>, std::string> registered_;  // (kind, name) -> file path
  std::map<std::string, std::shared_ptr<const GpuEnvironment>> environments_;
  std::map<std::string, std::shared_ptr<const GpuMesh>> meshes_;
  std::map<std::string, std::shared_ptr<const GpuTexture>> textures_;  // key: name + "|srgb" / "|linear"
  std::map<std::string, std::weak_ptr<const GpuEnvironment>> uploadedEnvironments_;
  std::map<std::string, std::weak_ptr<const GpuMesh>> uploadedMeshes_;
  std::map<std::string, std::weak_ptr<const GpuTexture>> uploadedTextures_;
  std::map<std::string, std::weak_ptr<const GpuMeasured>> uploadedMeasured_;
  std::map<std::string, std::shared_ptr<const GpuMeasured>> pinnedMeasured_;  // every registered table
};

}  // namespace brdfa
