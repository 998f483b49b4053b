#include "core/resources.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "core/errors.h"

namespace iphong {

std::uint64_t DefaultMemoryLimitBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  double total = pages > 0 && page > 0 ? static_cast<double>(pages) * page : 8e9;
  for (int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    rlimit limit{};
    if (::getrlimit(resource, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
      total = std::min(total, static_cast<double>(limit.rlim_cur));
    }
  }
  return static_cast<std::uint64_t>(0.75 * total);
}

std::uint64_t MemoryLimit::resolved() const {
  return bytes > 0 ? bytes : DefaultMemoryLimitBytes();
}

std::string FormatBytes(double bytes) {
  char text[32];
  if (bytes >= 1e9) {
    std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
  } else if (bytes >= 1e6) {
    std::snprintf(text, sizeof text, "%.0f MB", bytes / 1e6);
  } else {
    std::snprintf(text, sizeof text, "%.0f kB", std::max(bytes, 0.0) / 1e3);
  }
  return text;
}

std::string MemoryLimit::Check(double needed, const std::string& what) const {
  const double limit = static_cast<double>(resolved());
  if (needed <= limit) return "";
  return what + " needs " + FormatBytes(needed) + ", more than the memory limit of " +
         FormatBytes(limit) + " (raise it with " + knob + ")";
}

void RequireMemory(const MemoryLimit& limit, double needed, const std::string& what) {
  if (std::string message = limit.Check(needed, what); !message.empty()) {
    throw ResourceError(message);
  }
}

}  // namespace iphong
