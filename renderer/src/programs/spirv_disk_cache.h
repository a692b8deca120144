// SPIR-V kept on disk by content: the key hashes the assembled program, the shader stage and
// the compiler version, never a BRDF's name, so a renamed BRDF hits and a new glslang misses.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace brdfa {

class SpirvDiskCache {
 public:
  // An empty `dir` disables the cache. With `loadEntries` false it only writes (the thesis's
  // --no-cache-load: rebuild everything, refresh the cache).
  SpirvDiskCache(std::string dir, bool loadEntries);

  // The words stored under `key` for a source of `sourceBytes` bytes; nullopt when absent,
  // disabled, unreadable or not well formed (a corrupt file is a miss, never an error).
  std::optional<std::vector<uint32_t>> load(uint64_t key, uint64_t sourceBytes) const;

  // Stores atomically (temporary file, fsync, rename); failures are ignored: a cache.
  void store(uint64_t key, uint64_t sourceBytes, const std::vector<uint32_t>& words) const;

 private:
  std::string path(uint64_t key) const;
  std::string dir_;
  bool load_;
};

}  // namespace brdfa
