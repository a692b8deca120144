#include "storage/brdf_catalog.h"

#include <algorithm>
#include <filesystem>

#include "auth/identity.h"

namespace brdfa::server {

namespace fs = std::filesystem;

namespace {

std::string presetKey(std::string_view name) {
  std::string key(name);
  std::replace(key.begin(), key.end(), '/', '~');
  return key;
}

}  // namespace

std::vector<std::string> BrdfCatalog::load(const std::string& builtinDir, const std::string& dataDir) {
  dataDir_ = dataDir;
  std::vector<std::string> log = course_.loadBuiltins(builtinDir);
  for (std::string& msg : course_.loadUserDir((fs::path(dataDir) / "brdfs").string())) log.push_back(std::move(msg));
  course_.onRemoved([this](std::string_view name) { removePresetsOf(name); });
  for (std::string& msg : log) msg = "warning: " + msg;
  return log;
}

BrdfLibrary* BrdfCatalog::openStudentLocked(const std::string& user, bool create) {
  if (auto it = students_.find(user); it != students_.end()) return it->second.get();
  const fs::path dir = fs::path(dataDir_) / "users" / user / "brdfs";
  std::error_code ec;
  // Only a save makes a folder: a read of `anyone/x` must not leave one behind for every name.
  if (!create && !fs::is_directory(dir, ec)) return nullptr;
  auto library = std::make_unique<BrdfLibrary>();
  for (const std::string& msg : library->loadUserDir(dir.string(), user))
    std::fprintf(stderr, "warning: %s\n", msg.c_str());
  library->onRemoved([this](std::string_view name) { removePresetsOf(name); });
  return students_.emplace(user, std::move(library)).first->second.get();
}

BrdfLibrary* BrdfCatalog::libraryFor(std::string_view name, bool create) {
  if (!isValidQualifiedBrdfName(name)) return nullptr;
  const std::string_view owner = brdfNameOwner(name);
  if (owner.empty()) return &course_;
  std::lock_guard lock(mutex_);
  return openStudentLocked(std::string(owner), create);
}

void BrdfCatalog::discoverStudents() {
  std::vector<std::string> users;
  std::error_code ec;
  for (fs::directory_iterator it(fs::path(dataDir_) / "users", ec), end; !ec && it != end; it.increment(ec)) {
    const std::string user = it->path().filename().string();
    if (isValidUserName(user)) users.push_back(user);
  }
  std::lock_guard lock(mutex_);
  for (const std::string& user : users) openStudentLocked(user, false);
}

std::shared_ptr<const BrdfEntry> BrdfCatalog::find(std::string_view name) {
  BrdfLibrary* library = libraryFor(name);
  return library ? library->find(name) : nullptr;
}

std::optional<BrokenBrdf> BrdfCatalog::findBroken(std::string_view name) {
  BrdfLibrary* library = libraryFor(name);
  return library ? library->findBroken(name) : std::nullopt;
}

std::vector<std::shared_ptr<const BrdfEntry>> BrdfCatalog::list() {
  discoverStudents();
  std::vector<std::shared_ptr<const BrdfEntry>> out = course_.list();
  std::lock_guard lock(mutex_);
  for (const auto& [user, library] : students_)
    for (auto& entry : library->list()) out.push_back(std::move(entry));
  return out;
}

std::vector<BrokenBrdf> BrdfCatalog::listBroken() {
  discoverStudents();
  std::vector<BrokenBrdf> out = course_.listBroken();
  std::lock_guard lock(mutex_);
  for (const auto& [user, library] : students_)
    for (BrokenBrdf& b : library->listBroken()) out.push_back(std::move(b));
  return out;
}

std::string BrdfCatalog::presetDir(std::string_view person, std::string_view name) const {
  const fs::path root =
      person.empty() ? fs::path(dataDir_) / "presets" : fs::path(dataDir_) / "users" / std::string(person) / "presets";
  return (root / presetKey(name)).string();
}

void BrdfCatalog::removePresetsOf(std::string_view name) const {
  std::error_code ec;
  fs::remove_all(presetDir("", name), ec);
  for (fs::directory_iterator it(fs::path(dataDir_) / "users", ec), end; !ec && it != end; it.increment(ec)) {
    const std::string user = it->path().filename().string();
    std::error_code rmError;
    if (isValidUserName(user)) fs::remove_all(presetDir(user, name), rmError);
  }
}

}  // namespace brdfa::server
