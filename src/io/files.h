// Whole files in and out. Reads refuse what is not a regular file (a FIFO or /dev/zero named as
// a light file would hang or fill the memory) and text larger than a light file can be; writes are
// verified: every byte written, the file flushed to the disk (fsync) and its size checked, so a
// full disk or a quota is an error, never a short file reported as success.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace iphong::io {

// The extension of `path`, lower case, with its dot (".exr"; "" when there is none): what the
// readers and writers choose a format by.
std::string LowerExtension(const std::string& path);

// Whether anything is at `path` (a file, a folder, a link that resolves); an error reads as no.
bool Exists(const std::string& path);

// Throws std::runtime_error "PATH: no such file" / "PATH: is a folder, not a file" / "PATH: not
// a regular file" unless `path` is a regular file (symbolic links followed). Returns its size.
std::uint64_t RequireRegularFile(const std::string& path);

// A text input (light files, filenames.txt, JSON): throws std::runtime_error naming the file when
// it is missing, not a regular file, larger than `max_bytes` or unreadable.
std::string ReadTextFile(const std::string& path, std::uint64_t max_bytes = 64u << 20);

// Creates `path` (which must not exist: outputs are staged in folders of their own) with exactly
// `bytes`, then fsync, close and a size check. Throws OutputError "PATH: cannot write: REASON"
// and removes what it created.
void WriteFileVerified(const std::string& path, std::string_view bytes);

// Text outputs (JSON, light files) go through WriteFileVerified.
inline void WriteTextFile(const std::string& path, const std::string& text) {
  WriteFileVerified(path, text);
}

// After a file written by a library to `path` (matio writes only to paths): fsync it, check it
// is not empty. Throws OutputError naming the file.
void SyncWrittenFile(const std::string& path);

// fsync of a folder, so the names in it (new files, renames) survive a crash. Throws OutputError.
void SyncFolder(const std::string& path);

}  // namespace iphong::io
