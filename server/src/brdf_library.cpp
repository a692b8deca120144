#include "brdfa_server/brdf_library.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace brdfa::server {

bool isReservedBrdfName(std::string_view name) { return name == "inline" || name == "validate"; }

bool isValidBrdfName(std::string_view name) {
  if (name.empty() || name.size() > 64 || isReservedBrdfName(name)) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
}

std::vector<std::string> BrdfLibrary::loadBuiltins(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> messages;
  std::error_code ec;
  fs::directory_iterator it(dir, ec);
  if (ec) {
    messages.push_back("cannot read BRDF directory " + dir + ": " + ec.message());
    return messages;
  }
  std::map<std::string, std::shared_ptr<const BrdfEntry>, std::less<>> loaded;
  for (const fs::directory_entry& file : it) {
    const fs::path& path = file.path();
    if (path.extension() != ".brdf" || !file.is_regular_file(ec)) continue;
    std::string name = path.stem().string();
    if (!isValidBrdfName(name)) {
      messages.push_back("skipping " + path.string() + ": not a valid BRDF name");
      continue;
    }
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) {
      messages.push_back("skipping " + path.string() + ": cannot read");
      continue;
    }
    Result<BrdfDefinition> parsed = parseBrdf(text.str());
    if (!parsed) {
      std::string msg = "skipping " + path.string() + ": " + parsed.error().message;
      for (const Diagnostic& d : parsed.error().diagnostics)
        msg += "\n  line " + std::to_string(d.line) + ": " + d.message;
      messages.push_back(msg);
      continue;
    }
    auto entry = std::make_shared<BrdfEntry>();
    entry->name = name;
    entry->source = text.str();
    entry->definition = std::make_shared<const BrdfDefinition>(std::move(parsed.value()));
    entry->builtin = true;
    loaded[name] = std::move(entry);
  }
  std::lock_guard lock(mutex_);
  for (auto& [name, entry] : loaded) entries_[name] = entry;
  return messages;
}

std::shared_ptr<const BrdfEntry> BrdfLibrary::find(std::string_view name) const {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(name);
  return it == entries_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<const BrdfEntry>> BrdfLibrary::list() const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<const BrdfEntry>> out;
  out.reserve(entries_.size());
  for (const auto& [name, entry] : entries_) out.push_back(entry);
  return out;
}

BrdfLibrary::PutOutcome BrdfLibrary::putUser(std::string name, std::string source,
                                             std::shared_ptr<const BrdfDefinition> def) {
  auto entry = std::make_shared<BrdfEntry>();
  entry->name = name;
  entry->source = std::move(source);
  entry->definition = std::move(def);
  entry->builtin = false;
  std::lock_guard lock(mutex_);
  auto it = entries_.find(name);
  if (it != entries_.end() && it->second->builtin) return PutOutcome::BuiltinConflict;
  PutOutcome outcome = it == entries_.end() ? PutOutcome::Created : PutOutcome::Replaced;
  entries_[std::move(name)] = std::move(entry);
  return outcome;
}

BrdfLibrary::RemoveOutcome BrdfLibrary::remove(std::string_view name) {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(name);
  if (it == entries_.end()) return RemoveOutcome::NotFound;
  if (it->second->builtin) return RemoveOutcome::Builtin;
  entries_.erase(it);
  return RemoveOutcome::Removed;
}

}  // namespace brdfa::server
