// Memory checked before it is allocated. A request that would need more than the limit is refused
// with the figure and the limit instead of being tried: a 200-byte PNG header that declares
// 100000×100000 pixels, or a ring of 100 000 lights rendered one image each, must end in one
// clear line, not in minutes of swapping and std::bad_alloc.
#pragma once

#include <cstdint>
#include <string>

namespace iphong {

struct MemoryLimit {
  std::uint64_t bytes = 0;  // 0 = DefaultMemoryLimitBytes()
  // How the user raises it, quoted in the refusal ("--memory-limit" on the command line,
  // "max_memory_gb=" in Python).
  std::string knob = "--memory-limit";

  std::uint64_t resolved() const;
  // "" when `needed` bytes fit; else "WHAT needs 79.1 GB, more than the memory limit of 17.6 GB
  // (raise it with --memory-limit)".
  std::string Check(double needed, const std::string& what) const;
};

// Three quarters of the physical memory, or of the address-space / data-segment limit
// (ulimit -v / -d) when that is lower: the rest is left to the OS, the libraries' own buffers and
// the estimates' slack.
std::uint64_t DefaultMemoryLimitBytes();

// A memory size as people write it: "16", "16GB", "16 GB", "16G", "512M", "512MB", "1.5GiB",
// "800k", "2e9B", any case. A plain number is GB (--memory-limit's unit); k, M, G, T are decimal
// (as Dask reads "16GB"), KiB, MiB, GiB, TiB binary, B bytes. Between one byte and 1e18 bytes
// (1e9 GB). Returns "" and sets *bytes, or says what is wrong.
std::string ParseMemorySize(const std::string& text, std::uint64_t* bytes);
// The same for a number of GB (Python's max_memory_gb=).
std::string MemorySizeFromGb(double gb, std::uint64_t* bytes);

// "1.2 GB", "340 MB", "12 kB".
std::string FormatBytes(double bytes);

// Throws ResourceError with MemoryLimit::Check's message unless the request fits.
void RequireMemory(const MemoryLimit& limit, double needed, const std::string& what);

}  // namespace iphong
