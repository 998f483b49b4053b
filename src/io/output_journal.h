// The files behind OutputFolder's promises (io/output_folder.h), for io's own use: the manifest
// of what iphong wrote in a folder, the journal of a commit in progress and its recovery, the
// names of staging folders, and the lock that keeps one writer per folder.
//
// Layout of an output folder:
//   .iphong-manifest.json   {"generator", "note", "commands": {CMD: {NAME: {size, mtime_ns}}}}
//   .iphong-commit.json     {"staging": ".iphong-partial-PID-N", "move": [NAME..., manifest last],
//                            "remove": [{name, size, mtime_ns}...]}; present only mid-commit
//   .iphong-partial-PID-N/  a run's staged files (beside a new folder: .DIR.iphong-partial-PID-N)
#pragma once

#include <sys/stat.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "io/output_folder.h"

namespace iphong::io::internal {

constexpr const char* kManifest = ".iphong-manifest.json";
constexpr const char* kJournal = ".iphong-commit.json";
constexpr const char* kPartial = ".iphong-partial-";

using Manifest = std::map<std::string, std::map<std::string, ManifestEntry>>;

// "PID-N", unique per process and per output.
std::string PartialSuffix();
// ".iphong-partial-PID-N" exactly.
bool IsStagingName(const std::string& name);
// False only when the process that made a staging name is gone.
bool MadeByLiveProcess(const std::string& name);

// Absolute, symbolic links resolved as far as the path exists.
std::filesystem::path Resolve(const std::string& path);
// Component-wise: is `inner` equal to `outer` or inside it?
bool Within(const std::filesystem::path& inner, const std::filesystem::path& outer);

std::int64_t MtimeNs(const struct stat& st);
// A regular file of the recorded size and time.
bool Unchanged(const std::filesystem::path& path, const ManifestEntry& entry);

// Throws OutputError naming the manifest when it cannot be read.
Manifest ReadManifest(const std::filesystem::path& folder);
std::string ManifestText(const Manifest& manifest);

// fsync of a folder and every folder below it.
void SyncTree(const std::filesystem::path& root);

// Moves the staged files into place, removes the old files no longer produced (only while
// unchanged), then drops the journal and the staging folder. Every step is idempotent, so a run
// cut off here is finished by running it again.
void ApplyJournal(const std::filesystem::path& folder, const nlohmann::json& journal);

// With the folder locked: finishes a journal, removes staging folders of runs that are gone.
void RecoverLocked(const std::filesystem::path& folder);

// flock on a folder: its descriptor, −1 when another holds it, −2 when it cannot be opened.
int LockFolder(const std::filesystem::path& folder);

}  // namespace iphong::io::internal
