#include "core/resources.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

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

namespace {

// Checked before the conversion: a double past 2^64 does not convert to an integer.
std::string SizeFromBytes(double b, std::uint64_t* bytes) {
  if (std::isnan(b) || !(b > 0)) return "must be a size > 0";
  if (b < 1) return "is less than one byte";
  if (!(b <= 1e18)) return "is more than 1e9 GB";
  *bytes = static_cast<std::uint64_t>(b);
  return "";
}

}  // namespace

std::string MemorySizeFromGb(double gb, std::uint64_t* bytes) {
  return SizeFromBytes(gb * 1e9, bytes);
}

std::string ParseMemorySize(const std::string& text, std::uint64_t* bytes) {
  const std::string help = " (a size such as 16, 16GB, 512MB or 1.5GiB; a plain number is GB)";
  std::size_t used = 0;
  double value = 0;
  std::string trimmed = text;
  while (!trimmed.empty() && std::isspace(static_cast<unsigned char>(trimmed.back())))
    trimmed.pop_back();
  try {
    value = std::stod(trimmed, &used);
  } catch (const std::exception&) {
    return "'" + text + "' is not a size" + help;
  }
  std::string unit;
  for (std::size_t i = used; i < trimmed.size(); ++i) {
    if (!std::isspace(static_cast<unsigned char>(trimmed[i])))
      unit += static_cast<char>(std::tolower(static_cast<unsigned char>(trimmed[i])));
  }
  static const std::pair<const char*, double> kUnits[] = {{"", 1e9},
                                                          {"b", 1},
                                                          {"k", 1e3},
                                                          {"kb", 1e3},
                                                          {"m", 1e6},
                                                          {"mb", 1e6},
                                                          {"g", 1e9},
                                                          {"gb", 1e9},
                                                          {"t", 1e12},
                                                          {"tb", 1e12},
                                                          {"kib", 1024.0},
                                                          {"mib", 1048576.0},
                                                          {"gib", 1073741824.0},
                                                          {"tib", 1099511627776.0}};
  for (const auto& [name, scale] : kUnits) {
    if (unit != name) continue;
    if (std::string m = SizeFromBytes(value * scale, bytes); !m.empty())
      return "'" + text + "' " + m;
    return "";
  }
  return "'" + text + "' has an unknown unit '" + unit + "'" + help;
}

std::string FormatBytes(double bytes) {
  char text[32];
  if (bytes >= 1e9) {
    std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
  } else if (bytes >= 1e6) {
    std::snprintf(text, sizeof text, "%.0f MB", bytes / 1e6);
  } else if (bytes >= 1e3) {
    std::snprintf(text, sizeof text, "%.0f kB", bytes / 1e3);
  } else {
    std::snprintf(text, sizeof text, "%.0f B", std::max(bytes, 0.0));
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
