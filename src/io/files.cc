#include "io/files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "core/errors.h"

namespace iphong::io {

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

namespace {

[[noreturn]] void WriteFailed(const std::string& path, const std::string& why) {
  throw OutputError(path + ": cannot write: " + why);
}

// close() that keeps retrying nothing (Linux releases the descriptor even on EINTR) but reports.
int CloseReporting(int fd) { return ::close(fd) == 0 ? 0 : errno; }

}  // namespace

bool Exists(const std::string& path) {
  std::error_code error;
  return std::filesystem::exists(path, error);
}

std::uint64_t RequireRegularFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) throw std::runtime_error(path + ": no such file");
    throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) throw std::runtime_error(path + ": is a folder, not a file");
  if (!S_ISREG(st.st_mode)) {
    throw std::runtime_error(path + ": not a regular file (a device, pipe or socket)");
  }
  return static_cast<std::uint64_t>(st.st_size);
}

std::string ReadTextFile(const std::string& path, std::uint64_t max_bytes) {
  const std::uint64_t size = RequireRegularFile(path);
  if (size > max_bytes) {
    throw std::runtime_error(path + ": is " + std::to_string(size >> 20) +
                             " MB, too large for this text file (at most " +
                             std::to_string(max_bytes >> 20) + " MB)");
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::string text;
  text.resize(static_cast<std::size_t>(size));
  std::size_t done = 0;
  // The size may change while reading; read what is there, up to the limit.
  while (true) {
    if (done == text.size()) {
      if (text.size() >= max_bytes) break;
      text.resize(std::min<std::uint64_t>(max_bytes, text.size() + 4096));
    }
    const ssize_t n = ::read(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      ::close(fd);
      throw std::runtime_error(path + ": cannot read: " + std::strerror(error));
    }
    if (n == 0) break;
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  text.resize(done);
  return text;
}

void WriteFileVerified(const std::string& path, std::string_view bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) WriteFailed(path, std::strerror(errno));
  auto fail = [&](int error) {
    ::close(fd);
    ::unlink(path.c_str());
    WriteFailed(path, std::strerror(error));
  };
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(errno);
    if (n == 0) fail(EIO);
    done += static_cast<std::size_t>(n);
  }
  // Delayed allocation and network file systems report a full disk only here.
  if (::fsync(fd) != 0) fail(errno);
  struct stat st {};
  if (::fstat(fd, &st) != 0) fail(errno);
  if (static_cast<std::uint64_t>(st.st_size) != bytes.size()) fail(EIO);
  if (const int error = CloseReporting(fd); error != 0) {
    ::unlink(path.c_str());
    WriteFailed(path, std::strerror(error));
  }
}

void SyncWrittenFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) WriteFailed(path, std::strerror(errno));
  struct stat st {};
  const bool ok = ::fsync(fd) == 0 && ::fstat(fd, &st) == 0;
  const int error = ok ? 0 : errno;
  ::close(fd);
  if (!ok) WriteFailed(path, std::strerror(error));
  if (st.st_size == 0) WriteFailed(path, "the library wrote an empty file");
}

void SyncFolder(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) WriteFailed(path, std::strerror(errno));
  const bool ok = ::fsync(fd) == 0;
  const int error = ok ? 0 : errno;
  ::close(fd);
  if (!ok) WriteFailed(path, std::strerror(error));
}

}  // namespace iphong::io
