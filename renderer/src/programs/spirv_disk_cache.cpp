#include "programs/spirv_disk_cache.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace brdfa {

namespace {
constexpr char kMagic[8] = {'B', 'R', 'D', 'F', 'A', 'S', 'P', 'V'};
constexpr uint32_t kSpirvMagic = 0x07230203u;
constexpr uint64_t kMaxWords = 16u << 20;  // 64 MiB: anything larger is not ours

bool writeAll(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    ssize_t w = ::write(fd, p, n);
    if (w <= 0) return false;
    p += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}
}  // namespace

SpirvDiskCache::SpirvDiskCache(std::string dir, bool loadEntries) : dir_(std::move(dir)), load_(loadEntries) {
  if (dir_.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) dir_.clear();  // unusable: run without a disk cache
}

std::string SpirvDiskCache::path(uint64_t key) const {
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.spirv", static_cast<unsigned long long>(key));
  return dir_ + "/" + name;
}

// File: magic, key, source length, word count, words.
std::optional<std::vector<uint32_t>> SpirvDiskCache::load(uint64_t key, uint64_t sourceBytes) const {
  if (dir_.empty() || !load_) return std::nullopt;
  std::ifstream in(path(key), std::ios::binary);
  if (!in) return std::nullopt;
  char magic[8];
  uint64_t storedKey = 0, storedBytes = 0, count = 0;
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(&storedKey), 8);
  in.read(reinterpret_cast<char*>(&storedBytes), 8);
  in.read(reinterpret_cast<char*>(&count), 8);
  if (!in || std::memcmp(magic, kMagic, 8) != 0 || storedKey != key || storedBytes != sourceBytes || count == 0 ||
      count > kMaxWords)
    return std::nullopt;
  std::vector<uint32_t> words(count);
  in.read(reinterpret_cast<char*>(words.data()), static_cast<std::streamsize>(count * 4));
  if (!in || words[0] != kSpirvMagic || in.peek() != std::char_traits<char>::eof()) return std::nullopt;
  return words;
}

void SpirvDiskCache::store(uint64_t key, uint64_t sourceBytes, const std::vector<uint32_t>& words) const {
  if (dir_.empty()) return;
  const std::string target = path(key);
  // Unique among every process that shares the folder (replicas in containers may share a pid),
  // so two writers of one key never write into the same temp file.
  std::string name = target + ".tmp.XXXXXX";
  int fd = ::mkostemp(name.data(), O_CLOEXEC);
  if (fd < 0) return;
  ::fchmod(fd, 0644);
  const std::string tmp = name;
  const uint64_t count = words.size();
  bool ok = writeAll(fd, kMagic, 8) && writeAll(fd, &key, 8) && writeAll(fd, &sourceBytes, 8) &&
            writeAll(fd, &count, 8) && writeAll(fd, words.data(), words.size() * 4) && ::fsync(fd) == 0;
  ::close(fd);
  if (!ok || std::rename(tmp.c_str(), target.c_str()) != 0) ::unlink(tmp.c_str());
}

}  // namespace brdfa
