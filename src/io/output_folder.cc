#include "io/output_folder.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/errors.h"
#include "core/version.h"
#include "io/files.h"

namespace iphong::io {
namespace fs = std::filesystem;
namespace {

constexpr const char* kManifest = ".iphong-manifest.json";
constexpr const char* kJournal = ".iphong-commit.json";
constexpr const char* kPartial = ".iphong-partial-";

[[noreturn]] void Refuse(const std::string& message) { throw OutputError(message); }

std::string Quote(const std::string& command) { return "`iphong " + command + "`"; }

// Outputs not yet committed, for AbandonOutputFolders. Signals are per process, so this registry
// is the one piece of process-wide state in io; it holds only cleanup callbacks.
struct Registry {
  std::mutex mutex;
  std::map<const void*, std::function<void()>> abandon;
};
Registry& Outputs() {
  static Registry registry;
  return registry;
}
void Register(const void* key, std::function<void()> abandon) {
  std::lock_guard<std::mutex> lock(Outputs().mutex);
  Outputs().abandon[key] = std::move(abandon);
}
void Unregister(const void* key) {
  std::lock_guard<std::mutex> lock(Outputs().mutex);
  Outputs().abandon.erase(key);
}

// Unique per process and per output, so two outputs of one run never share a staging name.
std::string PartialSuffix() {
  static std::atomic<int> counter{0};
  return std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

// The end of "PID-N" starting at `at` (digits, '-', digits), or npos.
std::size_t StagingSuffixEnd(const std::string& text, std::size_t at) {
  auto digits = [&](std::size_t i) {
    const std::size_t start = i;
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
    return i > start ? i : std::string::npos;
  };
  const std::size_t dash = digits(at);
  if (dash == std::string::npos || dash >= text.size() || text[dash] != '-')
    return std::string::npos;
  return digits(dash + 1);
}

// The names iphong stages under: ".iphong-partial-PID-N" inside a folder.
bool IsStagingName(const std::string& name) {
  const std::size_t prefix = std::strlen(kPartial);
  return name.rfind(kPartial, 0) == 0 && StagingSuffixEnd(name, prefix) == name.size();
}

// The pid a partial name was made by (".iphong-partial-PID-N", ".NAME.iphong-partial-PID-N").
bool MadeByLiveProcess(const std::string& name) {
  const auto at = name.rfind(kPartial);
  if (at == std::string::npos) return true;  // not ours: treat as alive, never touched
  const long pid = std::strtol(name.c_str() + at + std::strlen(kPartial), nullptr, 10);
  if (pid <= 0) return true;
  return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH;
}

fs::path Resolve(const std::string& path) {
  std::error_code error;
  fs::path p = fs::weakly_canonical(fs::absolute(path), error);
  if (error) p = fs::absolute(path).lexically_normal();
  if (p.has_parent_path() && p.filename().empty()) p = p.parent_path();
  return p;
}

// Component-wise: is `inner` equal to `outer` or inside it?
bool Within(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin(), o = outer.begin();
  for (; o != outer.end(); ++o, ++i) {
    if (o->empty()) continue;
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}

std::int64_t MtimeNs(const struct stat& st) {
  return static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
}

bool Unchanged(const fs::path& path, const ManifestEntry& entry) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
         static_cast<std::uint64_t>(st.st_size) == entry.size && MtimeNs(st) == entry.mtime_ns;
}

using Manifest = std::map<std::string, std::map<std::string, ManifestEntry>>;

Manifest ReadManifest(const fs::path& folder) {
  const fs::path path = folder / kManifest;
  Manifest manifest;
  try {
    const nlohmann::json j = nlohmann::json::parse(ReadTextFile(path.string()));
    for (const auto& [command, files] : j.at("commands").items()) {
      auto& entries = manifest[command];
      for (const auto& [name, entry] : files.items()) {
        entries[name] = {entry.at("size").get<std::uint64_t>(),
                         entry.at("mtime_ns").get<std::int64_t>()};
      }
    }
  } catch (const std::exception& e) {
    Refuse(path.string() + ": not a manifest iphong can read (" + e.what() +
           "); nothing in the folder was touched");
  }
  return manifest;
}

std::string ManifestText(const Manifest& manifest) {
  nlohmann::json j;
  j["generator"] = std::string("iphong ") + kVersion;
  j["note"] =
      "The files iphong wrote here. iphong replaces or removes only these, and only while their "
      "size and time are as listed.";
  j["commands"] = nlohmann::json::object();
  for (const auto& [command, files] : manifest) {
    nlohmann::json entries = nlohmann::json::object();
    for (const auto& [name, e] : files)
      entries[name] = {{"size", e.size}, {"mtime_ns", e.mtime_ns}};
    j["commands"][command] = entries;
  }
  return j.dump(2) + "\n";
}

void SyncTree(const fs::path& root) {
  SyncFolder(root.string());
  std::error_code error;
  for (fs::recursive_directory_iterator it(root, error), end; !error && it != end;
       it.increment(error)) {
    if (it->is_directory(error)) SyncFolder(it->path().string());
  }
}

// Applies a journal: moves the staged files into place, removes the old files that are no longer
// produced (only while unchanged), then drops the journal and the staging folder. Every step is
// idempotent, so a run cut off here is finished by running this again.
void ApplyJournal(const fs::path& folder, const nlohmann::json& journal) {
  const fs::path staging = folder / journal.at("staging").get<std::string>();
  if (staging.parent_path() != folder || staging.filename().string().rfind(kPartial, 0) != 0) {
    Refuse((folder / kJournal).string() + ": names a staging folder iphong does not use");
  }
  for (const auto& item : journal.at("move")) {
    const std::string name = item.get<std::string>();
    const fs::path from = staging / name, to = folder / name;
    std::error_code error;
    if (!fs::exists(from, error)) continue;  // moved before the interruption
    fs::create_directories(to.parent_path(), error);
    if (::rename(from.c_str(), to.c_str()) != 0) {
      Refuse(to.string() + ": cannot move into place: " + std::strerror(errno) +
             " (the next iphong run into this folder finishes the commit)");
    }
  }
  for (const auto& item : journal.at("remove")) {
    const fs::path path = folder / item.at("name").get<std::string>();
    const ManifestEntry entry{item.at("size").get<std::uint64_t>(),
                              item.at("mtime_ns").get<std::int64_t>()};
    if (!Unchanged(path, entry)) continue;
    ::unlink(path.c_str());
    for (fs::path dir = path.parent_path(); dir != folder && Within(dir, folder);
         dir = dir.parent_path()) {
      if (::rmdir(dir.c_str()) != 0) break;  // not empty: someone else's files are in it
    }
  }
  SyncFolder(folder.string());
  ::unlink((folder / kJournal).c_str());
  std::error_code ignored;
  fs::remove_all(staging, ignored);
  SyncFolder(folder.string());
}

// With the folder locked: finishes a journal, removes staging folders of runs that are gone.
void RecoverLocked(const fs::path& folder) {
  const fs::path journal = folder / kJournal;
  std::error_code error;
  if (fs::exists(journal, error)) {
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(ReadTextFile(journal.string()));
    } catch (const std::exception& e) {
      Refuse(journal.string() + ": unreadable commit journal (" + e.what() +
             "); move it away to use this folder");
    }
    ApplyJournal(folder, j);
  }
  for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (IsStagingName(name) || name.rfind(std::string(kJournal) + kPartial, 0) == 0) {
      std::error_code ignored;
      fs::remove_all(it->path(), ignored);  // we hold the lock: nobody is writing there
    }
  }
}

// flock on a folder: one iphong writer per folder at a time. Returns −1 when another holds it.
int LockFolder(const fs::path& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return -2;
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
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
  Register(this, [this] { Abandon(); });
}

OutputFolder::~OutputFolder() {
  Unregister(this);
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
  // output of a joined command that is itself the input (integrate DIR -o DIR) is the exception.
  for (const std::string& input : options_.inputs) {
    if (input.empty()) continue;
    const fs::path in = Resolve(input);
    const bool same = in == target_;
    if (same && fs::exists(target_ / kManifest, error)) {
      const Manifest existing = ReadManifest(target_);
      bool joins = false;
      for (const std::string& other : options_.joins) joins |= existing.count(other) > 0;
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
  if (!staging_.empty() && !journaled_) fs::remove_all(staging_, ignored);
  staging_.clear();
  for (auto it = created_parents_.rbegin(); it != created_parents_.rend(); ++it) {
    if (::rmdir(it->c_str()) != 0) break;
  }
  created_parents_.clear();
}

void OutputFolder::Abandon() {
  std::lock_guard<std::mutex> lock(*mutex_);  // waits for a Commit in progress to finish
  if (committed_ || abandoned_) return;
  RemoveStaging();
  abandoned_ = true;
}

std::string WithoutStagingNames(const std::string& message) {
  // In each path component: ".NAME.iphong-partial-PID-N" (a new folder staged beside it) becomes
  // "NAME"; ".iphong-partial-PID-N/" (staged inside the folder) goes.
  std::string text = message;
  for (std::size_t at = text.find(kPartial); at != std::string::npos;
       at = text.find(kPartial, at + 1)) {
    const std::size_t end = StagingSuffixEnd(text, at + std::strlen(kPartial));
    if (end == std::string::npos) continue;
    const std::size_t slash = text.rfind('/', at);
    const std::size_t start = slash == std::string::npos ? 0 : slash + 1;
    if (start == at && end < text.size() && text[end] == '/') {
      text.erase(at, end + 1 - at);
      at = start;
    } else if (start < at && text[start] == '.' &&
               text.find(' ', start) > at) {  // one component: no space between
      text.erase(at, end - at);
      text.erase(start, 1);
      at = start;
    }
  }
  return text;
}

void AbandonOutputFolders() {
  std::lock_guard<std::mutex> lock(Outputs().mutex);
  for (auto& [key, abandon] : Outputs().abandon) abandon();
}

void FinishInterruptedCommit(const std::string& folder) {
  const fs::path path = Resolve(folder);
  std::error_code error;
  if (!fs::exists(path / kJournal, error)) return;
  const int fd = LockFolder(path);
  if (fd < 0) return;  // another iphong run holds it and will finish it
  try {
    RecoverLocked(path);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
}

void WriteSingleOutputFile(const std::string& path, bool overwrite,
                           const std::vector<std::string>& inputs,
                           const std::function<void(const std::string& temp)>& write) {
  const fs::path target = Resolve(path);
  for (const std::string& input : inputs) {
    if (!input.empty() && Resolve(input) == target) {
      Refuse(path + ": is an input; write the output to a file of its own");
    }
  }
  std::error_code error;
  const fs::file_status status = fs::symlink_status(target, error);
  if (fs::is_directory(status)) Refuse(path + ": is a folder; name a file for the output");
  if (fs::exists(status) && !overwrite) {
    Refuse(path + ": exists; pass --overwrite to replace it, or name a new file");
  }
  // The extension stays last: writers pick the format from it.
  const fs::path temp = target.parent_path() / ("." + target.stem().string() + kPartial +
                                                PartialSuffix() + target.extension().string());
  std::mutex mutex;  // before `partial`: its destructor unregisters the callback that uses it
  struct Temp {
    fs::path path;
    ~Temp() {
      Unregister(this);
      if (!path.empty()) ::unlink(path.c_str());
    }
  } partial{temp};
  Register(&partial, [&] {
    std::lock_guard<std::mutex> lock(mutex);
    if (!partial.path.empty()) ::unlink(partial.path.c_str());
    partial.path.clear();
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
  SyncFolder(target.parent_path().string());
}

}  // namespace iphong::io
