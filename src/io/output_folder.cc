#include "io/output_folder.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <deque>
#include <nlohmann/json.hpp>

#include "core/errors.h"
#include "io/files.h"
#include "io/output_journal.h"

namespace iphong::io {
namespace fs = std::filesystem;
using namespace internal;
namespace {

[[noreturn]] void Refuse(const std::string& message) { throw OutputError(message); }

std::string Quote(const std::string& command) { return "`iphong " + command + "`"; }

// Outputs not yet committed, for AbandonOutputFolders. Signals are per process, so this registry
// is the one piece of process-wide state in io; it holds only cleanup callbacks.
struct Registry {
  std::mutex mutex;
  std::map<const void*, std::function<bool()>> abandon;  // false: already committed
  std::map<const void*, std::string> targets;
  // Outputs committed and since released: a signal that comes after them (the process is still
  // finishing) reports them as complete, not as "nothing was written". Only the latest are kept:
  // a command writes one or two, and a Python session writing thousands must not grow this.
  std::deque<std::string> completed;
};
constexpr std::size_t kCompletedKept = 16;
Registry& Outputs() {
  // Never destroyed: a signal that arrives while the process exits still finds it whole.
  static Registry* registry = new Registry;
  return *registry;
}
void Register(const void* key, const std::string& target, std::function<bool()> abandon) {
  std::lock_guard<std::mutex> lock(Outputs().mutex);
  Outputs().abandon[key] = std::move(abandon);
  Outputs().targets[key] = target;
}
void Unregister(const void* key, bool complete) {
  std::lock_guard<std::mutex> lock(Outputs().mutex);
  if (complete) {
    Outputs().completed.push_back(Outputs().targets[key]);
    if (Outputs().completed.size() > kCompletedKept) Outputs().completed.pop_front();
  }
  Outputs().abandon.erase(key);
  Outputs().targets.erase(key);
}

bool ReservedName(const std::string& name) {
  return name == kManifest || name == kJournal || name.rfind(kPartial, 0) == 0;
}

}  // namespace

OutputFolder::OutputFolder(const std::string& target, OutputFolderOptions options)
    : options_(std::move(options)),
      target_display_(target),
      mutex_(std::make_shared<std::mutex>()) {
  try {
    Prepare(target);
  } catch (...) {
    RemoveStaging();
    if (lock_fd_ >= 0) ::close(lock_fd_);
    throw;
  }
  Register(this, target_display_, [this] { return Abandon(); });
}

OutputFolder::~OutputFolder() {
  bool complete = false;
  {
    std::lock_guard<std::mutex> lock(*mutex_);
    complete = committed_;
  }
  Unregister(this, complete);
  {
    std::lock_guard<std::mutex> lock(*mutex_);
    if (!committed_ && !abandoned_) RemoveStaging();
  }
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

void OutputFolder::Prepare(const std::string& target) {
  if (target.empty()) Refuse("-o: the output folder is an empty path");
  target_ = Resolve(target);
  std::error_code error;
  const fs::file_status status = fs::status(target_, error);
  target_existed_ = fs::exists(status);
  if (!target_existed_ && fs::exists(fs::symlink_status(target_, error))) {
    Refuse(target + ": is a symbolic link that leads nowhere (or in a loop); choose a folder");
  }
  if (target_existed_ && !fs::is_directory(status)) {
    Refuse(target + ": exists and is not a folder; choose a folder for the output");
  }

  // Inputs first: the output may not be one, lie inside one, or contain one. Adding to the
  // output of a joined command that is itself the input (integrate DIR -o DIR), or one of whose
  // files is (integrate DIR/normals.exr -o DIR), is the exception.
  for (const std::string& input : options_.inputs) {
    if (input.empty()) continue;
    const fs::path in = Resolve(input);
    const bool same = in == target_;
    const bool child = in.parent_path() == target_;
    if ((same || child) && fs::exists(target_ / kManifest, error)) {
      const Manifest existing = ReadManifest(target_);
      bool joins = false;
      for (const std::string& other : options_.joins) {
        const auto it = existing.find(other);
        joins |= it != existing.end() && (same || it->second.count(in.filename().string()) > 0);
      }
      if (joins && child) joined_inputs_.push_back(in.filename().string());
      if (joins) continue;
    }
    if (same || Within(target_, in) || Within(in, target_)) {
      Refuse(target + ": " +
             (same                  ? "is the input " + input
              : Within(target_, in) ? "lies inside the input " + input
                                    : "contains the input " + input) +
             "; write the output to a folder of its own (nothing was changed)");
    }
  }

  // The folder's own state decides what may happen: new, empty, or an earlier iphong output.
  bool empty = true;
  if (target_existed_) {
    lock_fd_ = LockFolder(target_);
    if (lock_fd_ == -1) Refuse(target + ": another iphong run is writing to this folder");
    if (lock_fd_ == -2) Refuse(target + ": cannot open the folder: " + std::strerror(errno));
    RecoverLocked(target_);
    for (fs::directory_iterator it(target_, error), end; !error && it != end; it.increment(error)) {
      empty = false;
      break;
    }
    if (error) Refuse(target + ": cannot list the folder: " + error.message());
    if (!empty) {
      if (!fs::exists(target_ / kManifest)) {
        Refuse(target +
               ": is not empty and was not written by iphong; choose a new or empty folder "
               "(nothing in it was touched)");
      }
      manifest_ = ReadManifest(target_);
      const bool same = manifest_.count(options_.command) > 0;
      bool joining = false;
      for (const std::string& other : options_.joins) joining |= manifest_.count(other) > 0;
      if (same && !options_.overwrite) {
        Refuse(target + ": holds an earlier " + Quote(options_.command) +
               " output; pass --overwrite to replace its files (nothing else in the folder is "
               "touched) or choose another folder");
      }
      if (!same && !joining && !manifest_.empty()) {
        Refuse(target + ": holds the output of " + Quote(manifest_.begin()->first) + ", which " +
               Quote(options_.command) + " does not add to; choose another folder");
      }
      in_place_ = true;
    }
  }

  if (in_place_) {
    staging_ = target_ / (kPartial + PartialSuffix());
    if (::mkdir(staging_.c_str(), 0777) != 0) {
      Refuse(target + ": cannot write in the folder: " + std::strerror(errno));
    }
    return;
  }
  // New or empty: stage beside it and rename once. Parent folders that do not exist are made
  // (and removed again if nothing is committed).
  const fs::path parent = target_.parent_path();
  std::vector<fs::path> missing;
  for (fs::path p = parent; !p.empty() && !fs::exists(p, error); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (::mkdir(it->c_str(), 0777) != 0 && errno != EEXIST) {
      Refuse(it->string() + ": cannot create the folder: " + std::strerror(errno));
    }
    created_parents_.push_back(*it);
  }
  // Staging folders of runs that were killed (SIGKILL cannot be caught) are ours to remove.
  const std::string prefix = "." + target_.filename().string() + kPartial;
  for (fs::directory_iterator it(parent, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) == 0 && !MadeByLiveProcess(name)) {
      std::error_code ignored;
      fs::remove_all(it->path(), ignored);
    }
  }
  staging_ = parent / (prefix + PartialSuffix());
  if (::mkdir(staging_.c_str(), 0777) != 0) {
    const int e = errno;
    if (target_existed_ && (e == EACCES || e == EPERM || e == EROFS)) {
      // An empty folder in a parent we may not write: stage inside it, move files one by one.
      staging_ = target_ / (kPartial + PartialSuffix());
      if (::mkdir(staging_.c_str(), 0777) == 0) {
        in_place_ = true;
        return;
      }
    }
    staging_.clear();
    Refuse(target + ": cannot create the output folder: " + std::strerror(e));
  }
}

std::string OutputFolder::file(const std::string& name) {
  std::lock_guard<std::mutex> lock(*mutex_);
  if (abandoned_ || committed_) Refuse(target_display_ + ": interrupted; nothing was written");
  const fs::path relative = fs::path(name).lexically_normal();
  if (name.empty() || relative.is_absolute() || *relative.begin() == ".." ||
      ReservedName(relative.begin()->string())) {
    throw std::logic_error("OutputFolder::file: bad name '" + name + "'");
  }
  const fs::path path = staging_ / relative;
  std::error_code error;
  fs::create_directories(path.parent_path(), error);
  if (error) Refuse(target_display_ + ": cannot create " + relative.parent_path().string());
  if (std::find(names_.begin(), names_.end(), relative.string()) == names_.end()) {
    names_.push_back(relative.string());
  }
  return path.string();
}

std::string OutputFolder::folder(const std::string& name) {
  std::lock_guard<std::mutex> lock(*mutex_);
  if (abandoned_ || committed_) Refuse(target_display_ + ": interrupted; nothing was written");
  const fs::path path = staging_ / fs::path(name).lexically_normal();
  std::error_code error;
  fs::create_directories(path, error);
  if (error) Refuse(target_display_ + ": cannot create " + name);
  return path.string();
}

void OutputFolder::Commit() {
  std::lock_guard<std::mutex> lock(*mutex_);
  if (abandoned_) Refuse(target_display_ + ": interrupted; nothing was written");
  if (committed_) return;
  // Every file handed out must exist: a writer that failed silently is caught here.
  std::map<std::string, ManifestEntry> written;
  for (const std::string& name : names_) {
    struct stat st {};
    if (::lstat((staging_ / name).c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
      Refuse((fs::path(target_display_) / name).string() + ": was not written");
    }
    written[name] = {static_cast<std::uint64_t>(st.st_size), MtimeNs(st)};
  }
  if (in_place_) {
    CommitInPlace(written);
  } else {
    WriteFileVerified((staging_ / kManifest).string(), ManifestText({{options_.command, written}}));
    SyncTree(staging_);
    CommitFresh();
  }
  committed_ = true;
}

void OutputFolder::CommitFresh() {
  if (target_existed_) {
    struct stat st {};
    if (::stat(target_.c_str(), &st) == 0) ::chmod(staging_.c_str(), st.st_mode & 07777);
  }
  // rename(2) replaces an empty folder and fails on a non-empty one: files that appeared in the
  // target meanwhile are never lost.
  if (::rename(staging_.c_str(), target_.c_str()) != 0) {
    const int e = errno;
    Refuse(target_display_ + ": cannot move the finished output into place: " +
           (e == ENOTEMPTY || e == EEXIST ? std::string("files appeared in it while iphong was "
                                                        "writing; nothing was changed")
                                          : std::string(std::strerror(e))));
  }
  staging_.clear();
  SyncFolder(target_.parent_path().string());
}

void OutputFolder::CommitInPlace(const std::map<std::string, ManifestEntry>& written) {
  Manifest manifest = manifest_;
  const std::map<std::string, ManifestEntry> previous =
      manifest_.count(options_.command) ? manifest_.at(options_.command)
                                        : std::map<std::string, ManifestEntry>{};
  auto& mine = manifest[options_.command];
  mine = written;
  // What is in the way of each new file: nothing, or a file iphong wrote and nobody changed.
  for (const std::string& name : names_) {
    const fs::path dest = target_ / name;
    for (fs::path dir = fs::path(name).parent_path(); !dir.empty(); dir = dir.parent_path()) {
      std::error_code error;
      if (fs::exists(fs::symlink_status(target_ / dir, error)) &&
          !fs::is_directory(fs::symlink_status(target_ / dir, error))) {
        Refuse((target_ / dir).string() + ": is in the way of " + name + " and is not a folder");
      }
    }
    if (std::find(joined_inputs_.begin(), joined_inputs_.end(), name) != joined_inputs_.end()) {
      throw std::logic_error(dest.string() + ": " + Quote(options_.command) +
                             " would replace its own input");
    }
    struct stat st {};
    if (::lstat(dest.c_str(), &st) != 0) continue;
    std::string owner;
    for (auto& [command, files] : manifest_) {
      if (files.count(name)) owner = command;
    }
    if (owner.empty()) {
      Refuse(dest.string() +
             ": exists and was not written by iphong; move it away or choose another folder "
             "(nothing was changed)");
    }
    if (!Unchanged(dest, manifest_.at(owner).at(name))) {
      Refuse(dest.string() + ": changed since " + Quote(owner) +
             " wrote it; move it away to keep it (nothing was changed)");
    }
    if (owner != options_.command) manifest[owner].erase(name);  // it becomes this command's
  }
  // Files of the earlier run of this command that this run does not write again.
  nlohmann::json remove = nlohmann::json::array();
  for (const auto& [name, entry] : previous) {
    if (mine.count(name)) continue;
    if (Unchanged(target_ / name, entry)) {
      remove.push_back({{"name", name}, {"size", entry.size}, {"mtime_ns", entry.mtime_ns}});
    }
  }
  for (auto it = manifest.begin(); it != manifest.end();) {
    it = it->second.empty() && it->first != options_.command ? manifest.erase(it) : std::next(it);
  }
  WriteFileVerified((staging_ / kManifest).string(), ManifestText(manifest));
  SyncTree(staging_);

  nlohmann::json journal;
  journal["staging"] = staging_.filename().string();
  journal["move"] = names_;
  journal["move"].push_back(kManifest);  // last: until it moves, the old manifest holds
  journal["remove"] = remove;
  const fs::path temp = target_ / (std::string(kJournal) + kPartial + PartialSuffix());
  WriteFileVerified(temp.string(), journal.dump(1) + "\n");
  if (::rename(temp.c_str(), (target_ / kJournal).c_str()) != 0) {
    const int e = errno;
    ::unlink(temp.c_str());
    Refuse(target_display_ + ": cannot write the commit journal: " + std::strerror(e));
  }
  SyncFolder(target_.string());  // the commit point: from here on the new state wins
  journaled_ = true;             // the staging folder now belongs to the journal
  ApplyJournal(target_, journal);
  staging_.clear();
}

void OutputFolder::RemoveStaging() {
  std::error_code ignored;
  // After the journal, what is staged is the new state: a failed or interrupted commit is
  // finished from it by the next run, so it stays.
  if (!staging_.empty() && !journaled_) {
    // Writer threads may still be creating files in it (an interrupt arrives mid-write, and
    // remove_all then meets a file made after it listed the folder, and leaves the folder).
    // Moved aside under a fresh staging name first, the paths they hold lead nowhere, so nothing
    // new appears in what is removed; were anything left, the next run removes it by its name.
    fs::path doomed = staging_;
    const std::string name = staging_.filename().string();
    const std::size_t at = name.find(kPartial);
    if (at != std::string::npos) {
      const fs::path aside =
          staging_.parent_path() / (name.substr(0, at + std::strlen(kPartial)) + PartialSuffix());
      if (::rename(staging_.c_str(), aside.c_str()) == 0) doomed = aside;
    }
    for (int attempt = 0; attempt < 3 && fs::exists(doomed, ignored); ++attempt)
      fs::remove_all(doomed, ignored);
  }
  staging_.clear();
  for (auto it = created_parents_.rbegin(); it != created_parents_.rend(); ++it) {
    if (::rmdir(it->c_str()) != 0) break;
  }
  created_parents_.clear();
}

bool OutputFolder::Abandon() {
  std::lock_guard<std::mutex> lock(*mutex_);  // waits for a Commit in progress to finish
  if (committed_) return false;
  if (!abandoned_) RemoveStaging();
  abandoned_ = true;
  return true;
}

AbandonReport AbandonOutputFolders() {
  std::lock_guard<std::mutex> lock(Outputs().mutex);
  AbandonReport report;
  report.complete.assign(Outputs().completed.begin(), Outputs().completed.end());
  for (auto& [key, abandon] : Outputs().abandon) {
    if (abandon()) {
      ++report.removed;
    } else {
      report.complete.push_back(Outputs().targets[key]);
    }
  }
  return report;
}

void WriteSingleOutputFile(const std::string& command, const std::string& path, bool overwrite,
                           const std::vector<std::string>& inputs,
                           const std::function<void(const std::string& temp)>& write) {
  const fs::path target = Resolve(path);
  // As for folders: not an input, and not inside one (an input folder is the user's dataset).
  for (const std::string& input : inputs) {
    if (input.empty()) continue;
    const fs::path in = Resolve(input);
    if (in == target) Refuse(path + ": is an input; write the output to a file of its own");
    if (Within(target, in)) {
      Refuse(path + ": lies inside the input " + input +
             "; write the output outside it (nothing was changed)");
    }
  }
  std::error_code error;
  const fs::file_status status = fs::symlink_status(target, error);
  if (fs::is_directory(status)) Refuse(path + ": is a folder; name a file for the output");
  // A file is written where its folder is: one that is missing is a typo as often as not.
  if (!fs::is_directory(target.parent_path(), error)) {
    const std::string where = fs::path(path).parent_path().string();
    Refuse(path + ": its folder " + (where.empty() ? target.parent_path().string() : where) +
           " does not exist; create it, or name a file in a folder that does");
  }
  if (fs::exists(status) && !overwrite) {
    Refuse(path + ": exists; pass --overwrite to replace it, or name a new file");
  }
  // Replacing: only a file iphong wrote there, unchanged since (the folder's manifest says so).
  const fs::path folder = target.parent_path();
  const std::string name = target.filename().string();
  auto listed = [&](const Manifest& manifest) {
    for (const auto& [cmd, files] : manifest) {
      const auto it = files.find(name);
      if (it != files.end() && Unchanged(target, it->second)) return true;
    }
    return false;
  };
  const bool manifest_exists = fs::exists(folder / kManifest, error);
  if (fs::exists(status) && !(manifest_exists && listed(ReadManifest(folder)))) {
    Refuse(path +
           ": exists and was not written by iphong (or was changed since); iphong replaces only "
           "its own files: name a new file");
  }
  // The extension stays last: writers pick the format from it.
  const fs::path temp = target.parent_path() / ("." + target.stem().string() + kPartial +
                                                PartialSuffix() + target.extension().string());
  std::mutex mutex;  // before `partial`: its destructor unregisters the callback that uses it
  struct Temp {
    fs::path path;
    bool placed = false;  // moved into place: complete
    ~Temp() {
      Unregister(this, placed);
      if (!path.empty()) ::unlink(path.c_str());
    }
  } partial{temp};
  Register(&partial, path, [&] {
    std::lock_guard<std::mutex> lock(mutex);
    if (partial.path.empty()) return false;  // in place: complete
    ::unlink(partial.path.c_str());
    partial.path.clear();
    return true;
  });
  write(temp.string());
  std::lock_guard<std::mutex> lock(mutex);
  if (partial.path.empty()) Refuse(path + ": interrupted; nothing was written");
  if (overwrite) {
    if (::rename(temp.c_str(), target.c_str()) != 0) {
      Refuse(path + ": cannot move the finished file into place: " + std::strerror(errno));
    }
  } else {
    // link(2) fails when the name exists, so a file that appeared meanwhile is never replaced.
    if (::link(temp.c_str(), target.c_str()) != 0) {
      Refuse(path + (errno == EEXIST ? std::string(": appeared while iphong was writing; kept")
                                     : ": cannot create: " + std::string(std::strerror(errno))));
    }
    ::unlink(temp.c_str());
  }
  partial.path.clear();
  partial.placed = true;
  // List it, so a later --overwrite may replace it: the manifest is rewritten whole and renamed
  // into place, keeping what other commands listed.
  struct stat st {};
  if (::lstat(target.c_str(), &st) == 0) {
    Manifest manifest = fs::exists(folder / kManifest, error) ? ReadManifest(folder) : Manifest{};
    manifest[command][name] = {static_cast<std::uint64_t>(st.st_size), MtimeNs(st)};
    const fs::path staged = folder / (std::string(kManifest) + kPartial + PartialSuffix());
    WriteFileVerified(staged.string(), ManifestText(manifest));
    if (::rename(staged.c_str(), (folder / kManifest).c_str()) != 0) {
      ::unlink(staged.c_str());
      Refuse((folder / kManifest).string() + ": cannot update: " + std::strerror(errno));
    }
  }
  SyncFolder(folder.string());
}

}  // namespace iphong::io
