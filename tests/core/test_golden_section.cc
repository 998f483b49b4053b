// The golden-section searches shared by the model choice (shininess) and the effective light
// distance (its distance in log x, its centre's depth in x): call count, distinct points, and
// convergence on closed-form unimodal functions.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

#include "core/golden_section.h"

namespace iphong {
namespace {

// f(x) = (log x − log 3)², minimum at x = 3, searched on [1, 10]. After n narrowings the bracket
// is (log 10)·0.618^(n+1) wide in log x, and the best point evaluated lies within it of log 3.
TEST(GoldenSection, FindsTheMinimumOfALogQuadraticWithinTheBracketsWidth) {
  for (int iterations : {0, 3, 4, 12}) {
    std::vector<double> xs;
    const auto f = [&](double x) {
      xs.push_back(x);
      return std::pow(std::log(x) - std::log(3.0), 2);
    };
    GoldenSectionLog(1.0, 10.0, iterations, f);
    ASSERT_EQ(xs.size(), static_cast<std::size_t>(2 + iterations));
    EXPECT_EQ(std::set<double>(xs.begin(), xs.end()).size(), xs.size());  // each a new x
    double best = xs[0];
    for (double x : xs) {
      EXPECT_GT(x, 1.0);
      EXPECT_LT(x, 10.0);
      if (std::abs(std::log(x / 3)) < std::abs(std::log(best / 3))) best = x;
    }
    const double width = std::log(10.0) * std::pow((std::sqrt(5.0) - 1) / 2, iterations + 1);
    EXPECT_LT(std::abs(std::log(best / 3)), width) << iterations << " iterations";
  }
}

// f(x) = (x − 0.3)², searched on [−1, 2]: after n narrowings the bracket is 3·0.618^(n+1) wide,
// and the best point evaluated lies within it of 0.3.
TEST(GoldenSection, FindsTheMinimumOfAQuadraticWithinTheBracketsWidth) {
  for (int iterations : {0, 5, 12}) {
    std::vector<double> xs;
    GoldenSection(-1.0, 2.0, iterations, [&](double x) {
      xs.push_back(x);
      return (x - 0.3) * (x - 0.3);
    });
    ASSERT_EQ(xs.size(), static_cast<std::size_t>(2 + iterations));
    EXPECT_EQ(std::set<double>(xs.begin(), xs.end()).size(), xs.size());
    double best = xs[0];
    for (double x : xs) {
      EXPECT_GT(x, -1.0);
      EXPECT_LT(x, 2.0);
      if (std::abs(x - 0.3) < std::abs(best - 0.3)) best = x;
    }
    EXPECT_LT(std::abs(best - 0.3), 3 * std::pow((std::sqrt(5.0) - 1) / 2, iterations + 1));
  }
}

}  // namespace
}  // namespace iphong
