// Nelder–Mead simplex search (Nelder and Mead 1965, with the standard coefficients of Lagarias et
// al. 1998: reflection 1, expansion 2, contraction ½, shrink ½) for a few parameters whose cost
// has no derivative to hand and runs along a diagonal valley, where searching one parameter at a
// time stalls (the effective light distance and its centre's depth). Written here because it is
// a page and none of iphong's libraries has one (Ceres and Eigen minimise with derivatives).
// The caller's `f` records what it evaluates and picks the best point among all it has scored.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <utility>
#include <vector>

namespace iphong {

// Starts from `simplex` (n + 1 points of n parameters, their costs already known: `cost`, the
// caller having scored them); stops once every vertex lies within tolerance_i of the best in each
// coordinate i, or after max_evaluations further calls of f. Returns the best point.
template <typename F>
std::vector<double> NelderMead(std::vector<std::vector<double>> simplex, std::vector<double> cost,
                               const std::vector<double>& tolerance, int max_evaluations, F&& f) {
  const std::size_t n = simplex.size() - 1;
  std::vector<std::vector<double>>& x = simplex;
  int evaluations = 0;
  const auto eval = [&](const std::vector<double>& p) {
    ++evaluations;
    return f(p);
  };
  std::vector<std::size_t> order(n + 1);
  const auto sort = [&] {
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return cost[a] < cost[b]; });
  };
  // p = centroid + t·(centroid − worst)
  const auto along = [&](const std::vector<double>& centroid, const std::vector<double>& worst,
                         double t) {
    std::vector<double> p(n);
    for (std::size_t i = 0; i < n; ++i) p[i] = centroid[i] + t * (centroid[i] - worst[i]);
    return p;
  };
  while (evaluations < max_evaluations) {
    sort();
    const std::size_t best = order[0], worst = order[n], second = order[n - 1];
    bool small = true;
    for (std::size_t v = 0; v <= n && small; ++v) {
      for (std::size_t i = 0; i < n; ++i) {
        if (std::abs(x[v][i] - x[best][i]) > tolerance[i]) small = false;
      }
    }
    if (small) break;
    std::vector<double> centroid(n, 0.0);
    for (std::size_t v = 0; v <= n; ++v) {
      if (v == worst) continue;
      for (std::size_t i = 0; i < n; ++i) centroid[i] += x[v][i] / static_cast<double>(n);
    }
    const std::vector<double> r = along(centroid, x[worst], 1);
    const double fr = eval(r);
    if (fr < cost[best]) {
      if (evaluations < max_evaluations) {
        const std::vector<double> e = along(centroid, x[worst], 2);
        const double fe = eval(e);
        if (fe < fr) {
          x[worst] = e, cost[worst] = fe;
          continue;
        }
      }
      x[worst] = r, cost[worst] = fr;
      continue;
    }
    if (fr < cost[second]) {
      x[worst] = r, cost[worst] = fr;
      continue;
    }
    if (evaluations >= max_evaluations) {
      if (fr < cost[worst]) x[worst] = r, cost[worst] = fr;
      break;
    }
    // Contract outside (the reflection beat the worst) or inside.
    const bool outside = fr < cost[worst];
    const std::vector<double> c = along(centroid, x[worst], outside ? 0.5 : -0.5);
    const double fc = eval(c);
    if (fc < (outside ? fr : cost[worst])) {
      x[worst] = c, cost[worst] = fc;
      continue;
    }
    // Shrink toward the best.
    for (std::size_t v = 0; v <= n && evaluations < max_evaluations; ++v) {
      if (v == best) continue;
      for (std::size_t i = 0; i < n; ++i) x[v][i] = x[best][i] + 0.5 * (x[v][i] - x[best][i]);
      cost[v] = eval(x[v]);
    }
  }
  sort();
  return x[order[0]];
}

// Starts from the simplex of `start` and start + step_i·e_i; f is called at most
// max_evaluations times, these n + 1 included.
template <typename F>
std::vector<double> NelderMead(const std::vector<double>& start, const std::vector<double>& step,
                               const std::vector<double>& tolerance, int max_evaluations, F&& f) {
  const std::size_t n = start.size();
  std::vector<std::vector<double>> x(n + 1, start);
  std::vector<double> cost(n + 1);
  for (std::size_t i = 0; i <= n; ++i) {
    if (i > 0) x[i][i - 1] += step[i - 1];
    if (static_cast<int>(i) >= max_evaluations) {
      // The budget ends before the simplex is whole: the best point scored.
      std::size_t best = 0;
      for (std::size_t v = 1; v < i; ++v) {
        if (cost[v] < cost[best]) best = v;
      }
      return x[best];
    }
    cost[i] = f(x[i]);
  }
  return NelderMead(std::move(x), std::move(cost), tolerance,
                    max_evaluations - static_cast<int>(n) - 1, std::forward<F>(f));
}

}  // namespace iphong
