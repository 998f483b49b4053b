// Output folders that appear complete or not at all: files go into a hidden sibling folder,
// which replaces the target only on Commit(). Destroyed uncommitted, it removes itself.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace iphong::io {

// Writes one file atomically: `write` gets a temporary path beside `path` (same extension, so
// libraries that pick the format from it pick the same one) and returns "" on success or what went
// wrong. Only a complete file replaces `path`; a failed one is removed. Throws std::runtime_error
// "PATH: what went wrong".
void WriteFileAtomically(const std::string& path,
                         const std::function<std::string(const std::string& temp)>& write);

class StagingDirectory {
 public:
  explicit StagingDirectory(const std::string& target);
  ~StagingDirectory();
  StagingDirectory(const StagingDirectory&) = delete;
  StagingDirectory& operator=(const StagingDirectory&) = delete;

  // Path of a file inside the staging folder.
  std::string file(const std::string& name) const { return (staging_ / name).string(); }
  // Moves the staging folder into place, replacing an existing target.
  void Commit();

 private:
  std::filesystem::path target_, staging_;
  bool committed_ = false;
};

}  // namespace iphong::io
