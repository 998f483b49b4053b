// Angular-error metrics (solve/metrics.h) on known angles.
#include <gtest/gtest.h>

#include <cmath>

#include "solve/metrics.h"

namespace iphong::solve {
namespace {

TEST(Metrics, KnownAnglesAndFractions) {
  ImageF gt(4, 1, 3), est(4, 1, 3);
  const double angles[4] = {1, 7, 15, 30};
  for (int i = 0; i < 4; ++i) {
    const double a = angles[i] * M_PI / 180;
    gt.pixels[3 * i + 2] = 1;
    est.pixels[3 * i] = static_cast<float>(std::sin(a));
    est.pixels[3 * i + 2] = static_cast<float>(std::cos(a));
  }
  const AngularErrorMetrics m = CompareNormals(est, gt, Mask(4, 1, true));
  EXPECT_EQ(m.pixels, 4u);
  EXPECT_NEAR(m.mean_deg, (1 + 7 + 15 + 30) / 4.0, 1e-5);
  EXPECT_NEAR(m.median_deg, 11.0, 1e-5);
  EXPECT_DOUBLE_EQ(m.below_5_deg, 0.25);
  EXPECT_DOUBLE_EQ(m.below_10_deg, 0.5);
  EXPECT_DOUBLE_EQ(m.below_20_deg, 0.75);
  EXPECT_NEAR(m.error_deg.pixels[3], 30, 1e-5);
}

}  // namespace
}  // namespace iphong::solve
