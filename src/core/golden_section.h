// Golden-section search of a unimodal function, of x (GoldenSection: an offset) or of log x
// (GoldenSectionLog: positive parameters searched on a ratio scale, a lobe's shininess, a light
// distance). The caller's `f` records what it evaluates and the caller picks the best point among
// all it has scored, grid points included.
#pragma once

#include <cmath>

namespace iphong {

// Brackets [lo, hi] and narrows them `iterations` times: f is called 2 + iterations times, each
// time at a new x.
template <typename F>
void GoldenSection(double lo, double hi, int iterations, F&& f) {
  const double r = (std::sqrt(5.0) - 1) / 2;
  double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < iterations; ++i) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - r * (hi - lo), f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + r * (hi - lo), f2 = f(x2);
    }
  }
}

// The same in log x, for lo_x, hi_x > 0.
template <typename F>
void GoldenSectionLog(double lo_x, double hi_x, int iterations, F&& f) {
  GoldenSection(std::log(lo_x), std::log(hi_x), iterations,
                [&](double u) { return f(std::exp(u)); });
}

}  // namespace iphong
