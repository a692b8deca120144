// The named BRDFs a scene can refer to: read-only built-ins from <root>/shaders/brdfs/*.brdf
// plus user BRDFs added over REST and saved as <data dir>/brdfs/<name>.brdf. Entries are
// immutable and shared: replacing a name swaps in a new entry, so a scene that resolved the old
// one keeps a valid definition. Thread-safe.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include <optional>

#include "brdfa/brdf.h"
#include "brdfa/result.h"

namespace brdfa::server {

// The web UI's per-tab working copies are user BRDFs named scratch-<session>: a batch test of
// "all" leaves them out (they are someone's unsaved edit, not the library).
// A student's are alice/scratch-<session>.
inline bool isScratchBrdf(std::string_view name) {
  const size_t slash = name.find('/');
  return name.substr(slash == std::string_view::npos ? 0 : slash + 1, 8) == "scratch-";
}

struct BrdfEntry {
  std::string name;    // "ggx", "my_ggx" (the course's), "alice/my_ggx" (a student's)
  std::string source;  // the .brdf text as submitted
  std::shared_ptr<const BrdfDefinition> definition;
  bool builtin = false;
  std::string owner;    // the student whose name it is under; "" for built-ins and the course
  bool shared = false;  // a student's, marked readable by everyone
};

// A saved user file that did not parse at start-up. Listed (with its error) so the user can see
// and fix or delete it; scenes cannot use it. A PUT of the name replaces it.
struct BrokenBrdf {
  std::string name;
  std::string source;
  Error error;        // CompileError with diagnostics, or why the file could not be read
  std::string owner;  // as BrdfEntry::owner
  bool shared = false;
};

// Names a client may give a BRDF or a preset: [A-Za-z0-9_-]{1,64}, minus the reserved ones.
bool isValidBrdfName(std::string_view name);
// "inline" (one-shot render's brdf_source), "validate" and "presets" (routes) cannot be stored.
bool isReservedBrdfName(std::string_view name);
// A BRDF's full name: a valid name, or <user>/<name> with a valid user name (identity.h).
bool isValidQualifiedBrdfName(std::string_view name);
// The owner part of a full name ("alice" of "alice/my_ggx"; "" for a bare name).
std::string_view brdfNameOwner(std::string_view name);

class BrdfLibrary {
 public:
  // Loads every <dir>/*.brdf as a built-in (parsed, never compiled here: compiling is left to
  // whoever first needs a BRDF, so start-up does not grow with the library). Files that fail
  // to parse are skipped; one message per skipped file is returned for the log.
  std::vector<std::string> loadBuiltins(const std::string& dir);

  // Makes `dir` the user store: removes stale temp files, then loads every <dir>/*.brdf as a
  // user BRDF (parsed only). A file that fails to parse becomes a BrokenBrdf; a file named like
  // a built-in (or not a valid name) is skipped. Later putUser/remove write to / unlink in `dir`.
  // With an `owner`, the store is that student's: its entries are named <owner>/<file stem>
  // and owned by them, and <stem>.shared beside a file marks it shared.
  // Returns one message per skipped or broken file for the log.
  std::vector<std::string> loadUserDir(const std::string& dir, const std::string& owner = {});

  std::shared_ptr<const BrdfEntry> find(std::string_view name) const;
  std::vector<std::shared_ptr<const BrdfEntry>> list() const;  // sorted by name

  std::vector<BrokenBrdf> listBroken() const;  // sorted by name
  std::optional<BrokenBrdf> findBroken(std::string_view name) const;

  enum class PutOutcome { Created, Replaced, BuiltinConflict, StoreFailed, QuotaExceeded };
  // Stores a user BRDF unless a built-in holds that name (built-ins are read-only). With a user
  // store, the file is written atomically first; when that fails (StoreFailed, `storeError` set)
  // nothing changes. A new name when the store already holds `maxEntries` (0: no limit) user
  // files is QuotaExceeded. A replaced BRDF keeps its sharing.
  // `stored`, when given, receives the entry this call stored (a concurrent remove may already
  // have taken it out of the library again by the time the caller looks).
  PutOutcome putUser(std::string name, std::string source, std::shared_ptr<const BrdfDefinition> def,
                     Error* storeError = nullptr, std::shared_ptr<const BrdfEntry>* stored = nullptr,
                     size_t maxEntries = 0);
  // User files in the store (broken ones too).
  size_t userEntryCount() const;

  // Marks a student's BRDF shared or not (its marker file); false when there is no such BRDF.
  Result<bool> setShared(std::string_view name, bool shared);

  // Called with a BRDF's name under the store lock whenever remove() took it out: the catalog
  // (brdf_catalog.h) removes every person's presets of it there.
  void onRemoved(std::function<void(std::string_view)> hook) { removeHook_ = std::move(hook); }

  enum class RemoveOutcome { Removed, NotFound, Builtin, StoreFailed };
  // Removes a user BRDF (or a broken one), its file, its sharing, and calls the remove hook.
  RemoveOutcome remove(std::string_view name, Error* storeError = nullptr);
  // Runs op(entry) (entry null when no BRDF holds `name`) while no BRDF is stored or removed:
  // a preset written or removed in op never interleaves with its BRDF's removal, so a preset
  // can neither outlive its BRDF nor pass to a later BRDF of the same name.
  template <class Op>
  auto withEntry(std::string_view name, Op&& op) {
    std::lock_guard store(storeMutex_);
    return op(find(name));
  }

  // <store>/<name>.brdf; empty without a user store.
  std::string userFilePath(std::string_view name) const;

  // Re-reads the user store when its folder changed since the last look (a save or delete by
  // another replica sharing the folder, docs/deploy.md). Every lookup above calls it first, so
  // a change on disk is seen by the next request; an unchanged folder costs one stat().
  void refreshUserDir() const;

 private:
  int64_t directoryStamp() const;  // the user store folder's mtime in ns; -1 when unreadable
  // Makes the user entries and broken files what the folder holds now (refreshMutex_ held).
  void rescanUserDirLocked(std::vector<std::string>* log);
  mutable std::mutex refreshMutex_;  // order: refreshMutex_ before mutex_
  mutable int64_t seenDirStamp_ = -2;
  // Each user file as the last scan saw it (refreshMutex_).
  struct FileStamp {
    uint64_t inode = 0;
    int64_t size = 0, mtimeNs = 0;
    bool operator==(const FileStamp&) const = default;
  };
  std::map<std::string, FileStamp, std::less<>> fileStamps_;

  // <store>/<stem>.shared, the marker of a shared BRDF.
  std::string sharedMarkerPath(std::string_view name) const;
  mutable std::mutex mutex_;
  // Serializes file writes with the map update, so the file on disk and the entry agree.
  std::mutex storeMutex_;
  std::string userDir_;  // set once by loadUserDir, before serving
  std::string owner_;    // set once by loadUserDir: "" for the course store
  std::function<void(std::string_view)> removeHook_;
  std::map<std::string, std::shared_ptr<const BrdfEntry>, std::less<>> entries_;
  std::map<std::string, BrokenBrdf, std::less<>> broken_;
};

}  // namespace brdfa::server
