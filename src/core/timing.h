// Wall-clock timing for solver summaries and CLI reports.
#pragma once

#include <chrono>

namespace iphong {

using Clock = std::chrono::steady_clock;

inline double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace iphong
