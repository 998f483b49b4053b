// Output folders that appear complete or not at all: files go into a hidden sibling folder,
// which replaces the target only on Commit(). Destroyed uncommitted, it removes itself.
#pragma once

#include <filesystem>
#include <string>

namespace iphong::io {

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

// Writes text to a file; throws std::runtime_error naming it.
void WriteTextFile(const std::string& path, const std::string& text);

}  // namespace iphong::io
