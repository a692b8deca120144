#include "storage/brdf_library.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "auth/identity.h"
#include "util/atomic_file.h"

namespace brdfa::server {

bool isReservedBrdfName(std::string_view name) { return name == "inline" || name == "validate" || name == "presets"; }

bool isValidBrdfName(std::string_view name) {
  if (name.empty() || name.size() > 64 || isReservedBrdfName(name)) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
}

bool isValidQualifiedBrdfName(std::string_view name) {
  const size_t slash = name.find('/');
  if (slash == std::string_view::npos) return isValidBrdfName(name);
  return isValidUserName(name.substr(0, slash)) && isValidBrdfName(name.substr(slash + 1));
}

std::string_view brdfNameOwner(std::string_view name) {
  const size_t slash = name.find('/');
  return slash == std::string_view::npos ? std::string_view() : name.substr(0, slash);
}

namespace {

// One *.brdf file read and parsed. `entry` on success, else `broken` (parse error) or, for
// files not to be listed at all, only a message.
struct LoadedFile {
  std::shared_ptr<BrdfEntry> entry;
  std::optional<BrokenBrdf> broken;
};

bool readWholeFile(const std::filesystem::path& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return false;
  out = text.str();
  return true;
}

std::shared_ptr<const BrdfEntry> makeEntry(const std::string& name, std::string source, BrdfDefinition definition,
                                           bool builtin, const std::string& owner = {}, bool shared = false) {
  auto entry = std::make_shared<BrdfEntry>();
  entry->name = name;
  entry->source = std::move(source);
  entry->definition = std::make_shared<const BrdfDefinition>(std::move(definition));
  entry->builtin = builtin;
  entry->owner = owner;
  entry->shared = shared;
  return entry;
}

// The same entry with another sharing (entries are immutable: scenes may hold the old one).
std::shared_ptr<const BrdfEntry> withShared(const std::shared_ptr<const BrdfEntry>& e, bool shared) {
  if (e->shared == shared) return e;
  auto copy = std::make_shared<BrdfEntry>(*e);
  copy->shared = shared;
  return copy;
}

std::string errorText(const Error& e) {
  std::string msg = e.message;
  for (const Diagnostic& d : e.diagnostics) msg += "\n  line " + std::to_string(d.line) + ": " + d.message;
  return msg;
}

// Calls `fn(name, path)` for every regular <dir>/<name>.brdf with a valid name (messages for
// the others). False when the folder cannot be read.
template <class Fn>
bool forEachBrdfFile(const std::string& dir, std::vector<std::string>& messages, Fn fn, const std::string& owner = {}) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::directory_iterator it(dir, ec);
  if (ec) {
    messages.push_back("cannot read BRDF directory " + dir + ": " + ec.message());
    return false;
  }
  for (const fs::directory_entry& file : it) {
    const fs::path& path = file.path();
    if (path.extension() != ".brdf" || !file.is_regular_file(ec)) continue;
    std::string name = path.stem().string();
    if (!isValidBrdfName(name)) {
      messages.push_back("skipping " + path.string() + ": not a valid BRDF name");
      continue;
    }
    fn(owner.empty() ? name : owner + "/" + name, path);
  }
  return true;
}

}  // namespace

std::vector<std::string> BrdfLibrary::loadBuiltins(const std::string& dir) {
  std::vector<std::string> messages;
  std::map<std::string, std::shared_ptr<const BrdfEntry>, std::less<>> loaded;
  forEachBrdfFile(dir, messages, [&](const std::string& name, const std::filesystem::path& path) {
    std::string text;
    if (!readWholeFile(path, text)) {
      messages.push_back("skipping " + path.string() + ": cannot read");
      return;
    }
    Result<BrdfDefinition> parsed = parseBrdf(text);
    if (!parsed) {
      messages.push_back("skipping " + path.string() + ": " + errorText(parsed.error()));
      return;
    }
    loaded[name] = makeEntry(name, std::move(text), std::move(parsed.value()), true);
  });
  std::lock_guard lock(mutex_);
  for (auto& [name, entry] : loaded) entries_[name] = entry;
  return messages;
}

std::vector<std::string> BrdfLibrary::loadUserDir(const std::string& dir, const std::string& owner) {
  std::vector<std::string> messages;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) messages.push_back("cannot create user BRDF directory " + dir + ": " + ec.message());
  if (int n = removeStaleTempFiles(dir); n > 0)
    messages.push_back("removed " + std::to_string(n) + " unfinished temp file(s) from " + dir);
  {
    std::lock_guard store(storeMutex_);
    userDir_ = dir;
    owner_ = owner;
  }
  std::lock_guard refresh(refreshMutex_);
  seenDirStamp_ = directoryStamp();
  rescanUserDirLocked(&messages);
  return messages;
}

int64_t BrdfLibrary::directoryStamp() const {
  struct stat st {};
  if (userDir_.empty() || ::stat(userDir_.c_str(), &st) != 0) return -1;
  return int64_t(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec;
}

void BrdfLibrary::refreshUserDir() const {
  if (userDir_.empty()) return;  // set once, before serving
  std::lock_guard refresh(refreshMutex_);
  const int64_t stamp = directoryStamp();
  const int64_t now =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  // A save or delete (by this server or another replica on the shared folder: a rename or an
  // unlink) changes the folder's mtime. One in the same clock tick as the previous scan would
  // leave it as it was, so a stamp less than a second old is never trusted.
  if (stamp == seenDirStamp_ && now - stamp > 1'000'000'000) return;
  seenDirStamp_ = stamp;
  const_cast<BrdfLibrary*>(this)->rescanUserDirLocked(nullptr);
}

void BrdfLibrary::rescanUserDirLocked(std::vector<std::string>* log) {
  std::vector<std::string> messages;
  std::map<std::string, std::shared_ptr<const BrdfEntry>, std::less<>> loaded;
  std::map<std::string, BrokenBrdf, std::less<>> broken;
  std::map<std::string, std::shared_ptr<const BrdfEntry>, std::less<>> current;
  std::map<std::string, BrokenBrdf, std::less<>> currentBroken;
  {
    std::lock_guard lock(mutex_);
    current = entries_;
    currentBroken = broken_;
  }
  std::map<std::string, FileStamp, std::less<>> stamps;
  if (!forEachBrdfFile(
          userDir_, messages,
          [&](const std::string& name, const std::filesystem::path& path) {
            auto it = current.find(name);
            std::error_code markerError;
            const bool shared = !owner_.empty() && std::filesystem::exists(sharedMarkerPath(name), markerError);
            if (it != current.end() && it->second->builtin) {
              messages.push_back("skipping " + path.string() + ": a built-in BRDF has that name");
              return;
            }
            // A file not replaced since the last scan (same inode, size and mtime: every save is a
            // new file renamed over the old) keeps its entry unread, so a young folder stamp, which
            // rescans on every lookup, costs a stat per file rather than a read and parse.
            struct stat st {};
            if (::stat(path.c_str(), &st) == 0) {
              const FileStamp stamp{uint64_t(st.st_ino), int64_t(st.st_size),
                                    int64_t(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec};
              stamps[name] = stamp;
              auto seen = fileStamps_.find(name);
              if (seen != fileStamps_.end() && seen->second == stamp) {
                if (it != current.end()) {
                  loaded[name] = withShared(it->second, shared);
                  return;
                }
                if (auto b = currentBroken.find(name); b != currentBroken.end()) {
                  broken[name] = b->second;
                  broken[name].shared = shared;
                  return;
                }
              }
            }
            std::string text;
            if (!readWholeFile(path, text)) {
              // Gone between the listing and the read (another replica's delete) is not broken.
              if (!std::filesystem::exists(path)) return;
              messages.push_back("user BRDF " + path.string() + " cannot be read; listed as broken");
              broken[name] =
                  BrokenBrdf{name, "", makeError(ErrorCode::Internal, "cannot read " + path.string()), owner_, shared};
              return;
            }
            // Unchanged: keep the entry (and its definition) that scenes already resolved.
            if (it != current.end() && it->second->source == text) {
              loaded[name] = withShared(it->second, shared);
              return;
            }
            Result<BrdfDefinition> parsed = parseBrdf(text);
            if (!parsed) {
              messages.push_back("user BRDF " + path.string() +
                                 " does not parse; listed as broken: " + errorText(parsed.error()));
              broken[name] = BrokenBrdf{name, std::move(text), parsed.takeError(), owner_, shared};
              return;
            }
            loaded[name] = makeEntry(name, std::move(text), std::move(parsed.value()), false, owner_, shared);
          },
          owner_)) {
    if (log) log->insert(log->end(), messages.begin(), messages.end());
    return;  // an unreadable folder changes nothing
  }
  fileStamps_ = std::move(stamps);
  std::lock_guard lock(mutex_);
  // The folder is the truth for user BRDFs: what it no longer holds is gone, what it holds now
  // is what was last written there.
  for (auto it = entries_.begin(); it != entries_.end();)
    it = !it->second->builtin && !loaded.count(it->first) ? entries_.erase(it) : std::next(it);
  for (auto& [name, entry] : loaded) entries_[name] = entry;
  broken_ = std::move(broken);
  if (log) log->insert(log->end(), messages.begin(), messages.end());
}

std::string BrdfLibrary::userFilePath(std::string_view name) const {
  if (userDir_.empty()) return {};
  const std::string_view stem = owner_.empty() ? name : name.substr(owner_.size() + 1);
  return (std::filesystem::path(userDir_) / (std::string(stem) + ".brdf")).string();
}

std::string BrdfLibrary::sharedMarkerPath(std::string_view name) const {
  std::string path = userFilePath(name);
  return path.substr(0, path.size() - 5) + ".shared";
}

size_t BrdfLibrary::userEntryCount() const {
  refreshUserDir();
  std::lock_guard lock(mutex_);
  size_t n = broken_.size();
  for (const auto& [name, entry] : entries_) n += entry->builtin ? 0 : 1;
  return n;
}

Result<bool> BrdfLibrary::setShared(std::string_view name, bool shared) {
  std::lock_guard store(storeMutex_);
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(name);
    if ((it == entries_.end() || it->second->builtin) && !broken_.count(name)) return false;
  }
  const std::string marker = sharedMarkerPath(name);
  if (shared) {
    BRDFA_TRY(writeFileAtomically(marker, ""));
  } else if (Result<void> removed = removeFileDurably(marker);
             !removed && removed.error().code != ErrorCode::NotFound) {
    return removed.takeError();
  }
  std::lock_guard lock(mutex_);
  if (auto it = entries_.find(name); it != entries_.end()) it->second = withShared(it->second, shared);
  if (auto it = broken_.find(name); it != broken_.end()) it->second.shared = shared;
  return true;
}

std::vector<BrokenBrdf> BrdfLibrary::listBroken() const {
  refreshUserDir();
  std::lock_guard lock(mutex_);
  std::vector<BrokenBrdf> out;
  for (const auto& [name, b] : broken_) out.push_back(b);
  return out;
}

std::optional<BrokenBrdf> BrdfLibrary::findBroken(std::string_view name) const {
  refreshUserDir();
  std::lock_guard lock(mutex_);
  auto it = broken_.find(name);
  if (it == broken_.end()) return std::nullopt;
  return it->second;
}

std::shared_ptr<const BrdfEntry> BrdfLibrary::find(std::string_view name) const {
  refreshUserDir();
  std::lock_guard lock(mutex_);
  auto it = entries_.find(name);
  return it == entries_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<const BrdfEntry>> BrdfLibrary::list() const {
  refreshUserDir();
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<const BrdfEntry>> out;
  out.reserve(entries_.size());
  for (const auto& [name, entry] : entries_) out.push_back(entry);
  return out;
}

BrdfLibrary::PutOutcome BrdfLibrary::putUser(std::string name, std::string source,
                                             std::shared_ptr<const BrdfDefinition> def, Error* storeError,
                                             std::shared_ptr<const BrdfEntry>* stored, size_t maxEntries) {
  if (maxEntries > 0) refreshUserDir();  // the count below is of what the folder holds now
  std::lock_guard store(storeMutex_);
  bool shared = false;
  bool exists = false;
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(name);
    if (it != entries_.end() && it->second->builtin) return PutOutcome::BuiltinConflict;
    exists = it != entries_.end() || broken_.count(name);
    shared = it != entries_.end() ? it->second->shared : exists && broken_.find(name)->second.shared;
    if (maxEntries > 0 && !exists) {
      size_t n = broken_.size();
      for (const auto& [other, entry] : entries_) n += entry->builtin ? 0 : 1;
      if (n >= maxEntries) return PutOutcome::QuotaExceeded;
    }
  }
  // Built-ins never change after start-up, so the check above still holds after the write.
  if (!userDir_.empty()) {
    Result<void> written = writeFileAtomically(userFilePath(name), source);
    if (!written) {
      if (storeError) *storeError = written.error();
      return PutOutcome::StoreFailed;
    }
  }
  auto entry = std::make_shared<BrdfEntry>();
  entry->name = name;
  entry->source = std::move(source);
  entry->definition = std::move(def);
  entry->builtin = false;
  entry->owner = owner_;
  entry->shared = shared;
  std::lock_guard lock(mutex_);
  // Decided before the write: a rescan by another request (refreshUserDir takes no store lock)
  // may have loaded the file just written, which does not make this save a replacement.
  const PutOutcome outcome = exists ? PutOutcome::Replaced : PutOutcome::Created;
  broken_.erase(name);
  if (stored) *stored = entry;
  entries_[std::move(name)] = std::move(entry);
  return outcome;
}

BrdfLibrary::RemoveOutcome BrdfLibrary::remove(std::string_view name, Error* storeError) {
  std::lock_guard store(storeMutex_);
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(name);
    if (it != entries_.end() && it->second->builtin) return RemoveOutcome::Builtin;
    if (it == entries_.end() && !broken_.count(name)) return RemoveOutcome::NotFound;
  }
  if (!userDir_.empty()) {
    Result<void> removed = removeFileDurably(userFilePath(name));
    if (!removed && removed.error().code != ErrorCode::NotFound) {
      if (storeError) *storeError = removed.error();
      return RemoveOutcome::StoreFailed;
    }
  }
  {
    std::lock_guard lock(mutex_);
    if (auto it = entries_.find(name); it != entries_.end()) entries_.erase(it);
    if (auto it = broken_.find(name); it != broken_.end()) broken_.erase(it);
  }
  // Its sharing and (through the hook) its presets go with it, still under the store lock, so a later BRDF of the
  // same name starts without stale ones (the BRDF is gone either way: a leftover preset file is
  // unreachable until then and is removed by the next remove of that name).
  if (!owner_.empty()) (void)removeFileDurably(sharedMarkerPath(name));  // absent when never shared
  if (removeHook_) removeHook_(name);
  return RemoveOutcome::Removed;
}

}  // namespace brdfa::server
