#include "io/staging.h"

#include <unistd.h>

#include <stdexcept>

namespace iphong::io {
namespace fs = std::filesystem;

void WriteFileAtomically(const std::string& path,
                         const std::function<std::string(const std::string& temp)>& write) {
  const fs::path target(path);
  const fs::path temp = target.parent_path() /
                        ("." + target.stem().string() + ".partial" + target.extension().string());
  std::error_code error;
  if (std::string failure = write(temp.string()); !failure.empty()) {
    fs::remove(temp, error);
    throw std::runtime_error(path + ": " + failure);
  }
  fs::rename(temp, target, error);
  if (error) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw std::runtime_error(path +
                             ": cannot move the finished file into place: " + error.message());
  }
}

StagingDirectory::StagingDirectory(const std::string& target)
    : target_(fs::absolute(target).lexically_normal()) {
  if (target_.filename().empty()) target_ = target_.parent_path();
  const fs::path parent = target_.parent_path();
  std::error_code error;
  fs::create_directories(parent, error);
  if (error) throw std::runtime_error(parent.string() + ": cannot create: " + error.message());
  staging_ =
      parent / ("." + target_.filename().string() + ".partial-" + std::to_string(::getpid()));
  fs::remove_all(staging_, error);
  fs::create_directory(staging_, error);
  if (error) throw std::runtime_error(staging_.string() + ": cannot create: " + error.message());
}

StagingDirectory::~StagingDirectory() {
  if (committed_) return;
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
}

void StagingDirectory::Commit() {
  std::error_code error;
  fs::path old;
  if (fs::exists(target_)) {
    old = target_.string() + ".old-" + std::to_string(::getpid());
    fs::rename(target_, old, error);
    if (error) {
      throw std::runtime_error(target_.string() +
                               ": cannot replace the existing folder: " + error.message());
    }
  }
  fs::rename(staging_, target_, error);
  if (error) {
    if (!old.empty()) fs::rename(old, target_, error);
    throw std::runtime_error(target_.string() + ": cannot move the finished output into place");
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, error);
}

}  // namespace iphong::io
