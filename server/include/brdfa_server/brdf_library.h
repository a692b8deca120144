// The named BRDFs a scene can refer to: read-only built-ins from <root>/shaders/brdfs/*.brdf
// plus user BRDFs added over REST. Entries are immutable and shared: replacing a name swaps in
// a new entry, so a scene that resolved the old one keeps a valid definition. Thread-safe.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "brdfa/brdf.h"
#include "brdfa/result.h"

namespace brdfa::server {

struct BrdfEntry {
  std::string name;
  std::string source;  // the .brdf text as submitted
  std::shared_ptr<const BrdfDefinition> definition;
  bool builtin = false;
};

// Names a client may give a BRDF: [A-Za-z0-9_-]{1,64}, minus the reserved ones.
bool isValidBrdfName(std::string_view name);
// "inline" (one-shot render's brdf_source) and "validate" (a route) cannot be stored.
bool isReservedBrdfName(std::string_view name);

class BrdfLibrary {
 public:
  // Loads every <dir>/*.brdf as a built-in (parsed, never compiled here: compiling is left to
  // whoever first needs a BRDF, so start-up does not grow with the library). Files that fail
  // to parse are skipped; one message per skipped file is returned for the log.
  std::vector<std::string> loadBuiltins(const std::string& dir);

  std::shared_ptr<const BrdfEntry> find(std::string_view name) const;
  std::vector<std::shared_ptr<const BrdfEntry>> list() const;  // sorted by name

  enum class PutOutcome { Created, Replaced, BuiltinConflict };
  // Stores a user BRDF unless a built-in holds that name (built-ins are read-only).
  PutOutcome putUser(std::string name, std::string source, std::shared_ptr<const BrdfDefinition> def);

  enum class RemoveOutcome { Removed, NotFound, Builtin };
  RemoveOutcome remove(std::string_view name);

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<const BrdfEntry>, std::less<>> entries_;
};

}  // namespace brdfa::server
