// Output folders: where a command's files go, and the rules that keep the user's files safe.
//
// - A command never deletes or changes a file it did not create.
// - `-o DIR` must be new, empty, or an earlier output of the same command, and then only with
//   `overwrite`. The manifest iphong keeps there (.iphong-manifest.json) lists the files it wrote,
//   with their sizes and times: only those are replaced or removed, and only if nobody changed
//   them since; anything else in the folder stays as it is. A command may also add its files to
//   the output of a command it `joins` (integrate beside the normals it integrates).
// - DIR may not be an input, lie inside one, or contain one.
// - Every file is written into a staging folder and verified (io/files.h); only Commit() shows
//   them. A new folder appears with one rename. In an existing folder a journal, written and
//   flushed before the first rename, lets the next run that opens the folder finish a commit that
//   was cut off (SIGKILL, power loss) between its renames.
// - Destroyed without Commit() — an error, an exception, or SIGINT/SIGTERM through
//   AbandonOutputFolders() — it removes its staging folder (and the parent folders it made), so
//   the target is exactly as it was.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace iphong::io {

struct OutputFolderOptions {
  std::string command;              // the iphong subcommand writing, e.g. "normals"
  bool overwrite = false;           // replace an earlier output of the same command
  std::vector<std::string> inputs;  // paths the command reads (files or folders)
  std::vector<std::string> joins;   // commands whose output folder this one may add files to
};

// A file iphong wrote, as the manifest remembers it.
struct ManifestEntry {
  std::uint64_t size = 0;
  std::int64_t mtime_ns = 0;
};

class OutputFolder {
 public:
  // Checks `target` against the rules and prepares the staging folder. Throws OutputError with a
  // one-line message naming the folder (or the file in the way) when the rules forbid it.
  OutputFolder(const std::string& target, OutputFolderOptions options);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  // Where to write `name` (relative, '/' for subfolders, which are created): a path in the
  // staging folder. The file must then be written, verified, by one of io's writers.
  std::string file(const std::string& name);
  // A subfolder of the staging folder, created, for reading back what was just written.
  std::string folder(const std::string& name);
  // Makes every file visible at once (see above). Throws OutputError; on failure the target is
  // left as it was (or, after the journal, is finished by the next run).
  void Commit();

  const std::string& target() const { return target_display_; }

 private:
  void Prepare(const std::string& target);
  void CommitFresh();
  void CommitInPlace(const std::map<std::string, ManifestEntry>& written);
  void RemoveStaging();
  bool Abandon();  // from AbandonOutputFolders: false when the output was already committed

  OutputFolderOptions options_;
  std::string target_display_;     // as the user wrote it, for messages
  std::filesystem::path target_;   // absolute, symlinks resolved
  std::filesystem::path staging_;  // where files are written until Commit
  bool in_place_ = false;          // target holds an earlier iphong output: files move one by one
  bool target_existed_ = false;
  int lock_fd_ = -1;  // flock on the target folder while writing in place
  std::vector<std::filesystem::path> created_parents_;
  std::vector<std::string> names_;  // files handed out, in order
  // Inputs that are a joined command's files in the target (integrate DIR/normals.exr -o DIR):
  // read, never replaced.
  std::vector<std::string> joined_inputs_;
  std::map<std::string, std::map<std::string, ManifestEntry>> manifest_;  // command -> files
  std::shared_ptr<std::mutex> mutex_;  // held by Commit and by AbandonOutputFolders
  bool committed_ = false, abandoned_ = false;
  bool journaled_ = false;  // the commit journal is written: the staging folder must stay
};

// Removes the staging folders (and partial single files) of every output not yet committed, and
// waits for one being committed to finish. For the command line's SIGINT/SIGTERM handling; safe
// from any thread. Says what it did: how many unfinished outputs it removed, and which outputs
// were complete (committed) by then, so the interrupt's message is true.
struct AbandonReport {
  std::size_t removed = 0;
  std::vector<std::string> complete;  // targets as the user wrote them
};
AbandonReport AbandonOutputFolders();

// Finishes a commit into `folder` that was cut off (its journal is present). Readers of an
// iphong output folder call this first, so they never see half of one run and half of another.
// Does nothing when another iphong process holds the folder.
void FinishInterruptedCommit(const std::string& folder);

// Messages from writers name the staging path (".out.iphong-partial-123-0/normals.exr"); this
// names the file where the user will look for it ("out/normals.exr").
std::string WithoutStagingNames(const std::string& message);

// A single output file (`eval --error-map`, `relight -o`): `write` writes it, verified, at the
// temporary path it is given; then it takes `path`'s name and is listed under `command` in the
// manifest of its folder, as output folders are. Without `overwrite` an existing `path` is an
// error and is never replaced; with it, only a file the manifest lists (iphong wrote it) and that
// nobody changed since is replaced, so a user's photo named by mistake stays as it is. `path` may
// not be one of `inputs` nor lie inside an input folder, even with `overwrite`. Throws
// OutputError.
void WriteSingleOutputFile(const std::string& command, const std::string& path, bool overwrite,
                           const std::vector<std::string>& inputs,
                           const std::function<void(const std::string& temp)>& write);

}  // namespace iphong::io
