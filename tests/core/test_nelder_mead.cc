// The simplex search the effective light distance uses for its distance and centre: convergence
// on closed-form valleys (Rosenbrock's, and a narrow diagonal quadratic where searching one
// coordinate at a time stalls), its evaluation budget, and its stopping tolerance.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/golden_section.h"
#include "core/nelder_mead.h"

namespace iphong {
namespace {

double Rosenbrock(const std::vector<double>& p) {
  return 100 * std::pow(p[1] - p[0] * p[0], 2) + std::pow(1 - p[0], 2);
}

TEST(NelderMead, FindsRosenbrocksMinimum) {
  int calls = 0;
  const std::vector<double> x =
      NelderMead({-1.2, 1.0}, {0.5, 0.5}, {1e-6, 1e-6}, 1000, [&](const std::vector<double>& p) {
        ++calls;
        return Rosenbrock(p);
      });
  EXPECT_NEAR(x[0], 1.0, 1e-4);
  EXPECT_NEAR(x[1], 1.0, 1e-4);
  EXPECT_LT(calls, 1000);  // stopped by the tolerance, not the budget
}

// f = 400 (x − y)² + (x + y − 1)²: a valley along x = y, minimum at (½, ½). Golden sections in x
// and y in turn, 13 evaluations each, from (0, 1): the valley's walls hold every step short.
TEST(NelderMead, FollowsADiagonalValleyWhereCoordinateSearchStalls) {
  const auto f = [](double x, double y) {
    return 400 * (x - y) * (x - y) + (x + y - 1) * (x + y - 1);
  };
  int calls = 0;
  const std::vector<double> x =
      NelderMead({0.0, 1.0}, {0.25, 0.25}, {1e-3, 1e-3}, 60, [&](const std::vector<double>& p) {
        ++calls;
        return f(p[0], p[1]);
      });
  EXPECT_LE(calls, 60);
  EXPECT_NEAR(x[0], 0.5, 0.01);
  EXPECT_NEAR(x[1], 0.5, 0.01);
  // The same 60 evaluations as two golden sections of 13 per round, each coordinate in turn.
  double cx = 0, cy = 1;
  for (int round = 0; round < 2; ++round) {
    double best = INFINITY, at = cx;
    GoldenSection(-1.0, 2.0, 11, [&](double u) {
      const double v = f(u, cy);
      if (v < best) best = v, at = u;
      return v;
    });
    cx = at, best = INFINITY, at = cy;
    GoldenSection(-1.0, 2.0, 11, [&](double u) {
      const double v = f(cx, u);
      if (v < best) best = v, at = u;
      return v;
    });
    cy = at;
  }
  EXPECT_GT(std::abs(cx - 0.5) + std::abs(cy - 0.5), 0.1);  // still far: what the simplex mends
}

TEST(NelderMead, KeepsToItsBudget) {
  for (int budget : {1, 2, 3, 4, 7, 20}) {
    int calls = 0;
    const std::vector<double> x = NelderMead({-1.2, 1.0}, {0.5, 0.5}, {1e-12, 1e-12}, budget,
                                             [&](const std::vector<double>& p) {
                                               ++calls;
                                               return Rosenbrock(p);
                                             });
    EXPECT_EQ(calls, budget);
    EXPECT_LE(Rosenbrock(x), Rosenbrock({-1.2, 1.0}));  // never worse than the start
  }
}

}  // namespace
}  // namespace iphong
