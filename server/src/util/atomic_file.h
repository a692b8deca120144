// Crash-safe file writes for the data folder (docs/design.md section 6): a reader, or the server
// after a crash at any moment, sees either the old complete file or the new complete file.
#pragma once

#include <chrono>
#include <filesystem>
#include <string_view>

#include "brdfa/result.h"

namespace brdfa::server {

// Temp files are named "<kTempPrefix><target name>.<random>" in the target's folder; loaders
// skip (and start-up removes) anything starting with kTempPrefix.
inline constexpr std::string_view kTempPrefix = ".tmp-";

// Writes `data` to a temp file in target's folder, fsyncs it, renames it over `target` and
// fsyncs the folder. Creates the folder (and its parents) when missing. Internal error on failure;
// the target is then untouched and no temp file is left behind.
Result<void> writeFileAtomically(const std::filesystem::path& target, std::string_view data);

// Like writeFileAtomically, but only when `target` does not exist yet (link(2) of the written
// temp file, atomic on a shared folder too): false in `created` when another writer had it.
Result<void> createFileExclusively(const std::filesystem::path& target, std::string_view data, bool& created);

// Unlinks `target` and fsyncs its folder. NotFound when it did not exist.
Result<void> removeFileDurably(const std::filesystem::path& target);

// A temp file this old is a crashed write, never one in progress (a write takes milliseconds).
inline constexpr std::chrono::minutes kTempFileAbandonedAfter{10};

// Removes leftover temp files (a crash between create and rename) older than
// kTempFileAbandonedAfter from `dir`; returns how many. Younger ones may be another replica's
// write in progress on a shared folder.
int removeStaleTempFiles(const std::filesystem::path& dir);

}  // namespace brdfa::server
