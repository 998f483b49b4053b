#include "io/output_journal.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>

#include "core/errors.h"
#include "core/version.h"
#include "io/files.h"

namespace iphong::io {
namespace fs = std::filesystem;

namespace internal {
namespace {

[[noreturn]] void Refuse(const std::string& message) { throw OutputError(message); }

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

}  // namespace

std::string PartialSuffix() {
  static std::atomic<int> counter{0};
  return std::to_string(::getpid()) + "-" + std::to_string(counter++);
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

}  // namespace internal

using namespace internal;

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

}  // namespace iphong::io
