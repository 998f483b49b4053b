// Flags and checks the subcommands share.
#include <filesystem>
#include <stdexcept>

#include "iphong/commands.h"

namespace iphong::cli {
namespace fs = std::filesystem;

void AddThreadsOption(CLI::App* cmd, CommonOptions& common) {
  cmd->add_option("--threads", common.threads, "Threads (0 = all cores)")
      ->check(CLI::Range(0, 1024));
}

void AddMemoryOption(CLI::App* cmd, CommonOptions& common) {
  cmd->add_option("--max-memory", common.max_memory_gb,
                  "Refuse work that needs more memory than this many GB (default: 3/4 of the "
                  "machine's)")
      ->check(CLI::PositiveNumber);
}

void AddOverwriteOption(CLI::App* cmd, CommonOptions& common) {
  cmd->add_flag("--overwrite", common.overwrite,
                "Replace the files of an earlier output of this command in -o (only those; "
                "nothing else in the folder is touched)");
}

void RequireFolder(const std::string& path) {
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (!fs::exists(status)) throw std::runtime_error(path + ": no such folder");
  if (!fs::is_directory(status)) throw std::runtime_error(path + ": is a file, not a folder");
}

}  // namespace iphong::cli
