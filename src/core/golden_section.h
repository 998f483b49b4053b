// Golden-section search of a unimodal function of log x, for positive parameters searched on a
// ratio scale (a lobe's shininess, a light distance). The caller's `f` records what it evaluates
// and the caller picks the best point among all it has scored, grid points included.
#pragma once

#include <cmath>

namespace iphong {

// Brackets [lo, hi] (both > 0) and narrows them `iterations` times: f is called 2 + iterations
// times, each time at a new x.
template <typename F>
void GoldenSectionLog(double lo_x, double hi_x, int iterations, F&& f) {
  const double r = (std::sqrt(5.0) - 1) / 2;
  double lo = std::log(lo_x), hi = std::log(hi_x);
  double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
  double f1 = f(std::exp(x1)), f2 = f(std::exp(x2));
  for (int i = 0; i < iterations; ++i) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - r * (hi - lo), f1 = f(std::exp(x1));
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + r * (hi - lo), f2 = f(std::exp(x2));
    }
  }
}

}  // namespace iphong
