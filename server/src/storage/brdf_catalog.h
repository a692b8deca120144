// Every BRDF a scene can name, across people: the built-ins and the course library (bare
// names, <data dir>/brdfs) and one library per student (`alice/...`, <data dir>/users/alice/brdfs),
// plus where each person's presets of a BRDF live. A student's library is opened on first use,
// and one made by another replica sharing the data folder is found on the next listing.
// Who may read or change what is the routes' business (identity.h); this only stores. Thread-safe.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "storage/brdf_library.h"

namespace brdfa::server {

class BrdfCatalog {
 public:
  // Loads the built-ins from `builtinDir` and the course library from <dataDir>/brdfs; the
  // students' libraries are opened when first named. Returns log lines.
  std::vector<std::string> load(const std::string& builtinDir, const std::string& dataDir);

  // The built-ins and the course library.
  BrdfLibrary& course() { return course_; }

  // The library that holds (or would hold) full name `name`: the course's for a bare name,
  // the student's for `user/...`. With `create`, a student's library folder is made when
  // missing; without, null when it does not exist (nobody saved under that name yet) or the
  // name is not a valid full name.
  BrdfLibrary* libraryFor(std::string_view name, bool create = false);

  std::shared_ptr<const BrdfEntry> find(std::string_view name);
  std::optional<BrokenBrdf> findBroken(std::string_view name);
  // Everything, sorted by name: built-ins, the course, then each student's.
  std::vector<std::shared_ptr<const BrdfEntry>> list();
  std::vector<BrokenBrdf> listBroken();

  // Where `person`'s presets of BRDF `name` live: <data>/presets/<key> for "" (the teacher,
  // and everyone in `none` mode), <data>/users/<person>/presets/<key> for a student; key is the
  // full name with '/' as '~' (a name of the layout before namespaces keeps its folder).
  std::string presetDir(std::string_view person, std::string_view name) const;

 private:
  // Opens every student library found under <data>/users that is not open yet.
  void discoverStudents();
  BrdfLibrary* openStudentLocked(const std::string& user, bool create);
  // Removes every person's presets of `name` (called under that library's store lock).
  void removePresetsOf(std::string_view name) const;

  std::string dataDir_;  // set once by load()
  BrdfLibrary course_;
  mutable std::mutex mutex_;
  std::map<std::string, std::unique_ptr<BrdfLibrary>, std::less<>> students_;
};

}  // namespace brdfa::server
