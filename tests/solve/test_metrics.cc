// Angular-error metrics (solve/metrics.h) on known angles.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

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

// Other tools write NaN where they found no normal: such a pixel is a missing normal (180°, as a
// zero estimate is), counted; an infinite component too, not a NaN angle in the mean; a map with
// no finite normal on the evaluated pixels is refused.
TEST(Metrics, NonFiniteEstimatesAreMissingNormalsCounted) {
  ImageF gt(4, 1, 3), est(4, 1, 3);
  for (int i = 0; i < 4; ++i) gt.pixels[3 * i + 2] = est.pixels[3 * i + 2] = 1;
  gt.pixels[3 * 1 + 2] = 0;  // no ground truth at pixel 1: not evaluated, whatever the estimate
  est.pixels[3 * 1] = std::numeric_limits<float>::quiet_NaN();
  est.pixels[3 * 2] = std::numeric_limits<float>::quiet_NaN();
  est.pixels[3 * 3 + 1] = std::numeric_limits<float>::infinity();
  const AngularErrorMetrics m = CompareNormals(est, gt, Mask(4, 1, true));
  EXPECT_EQ(m.pixels, 3u);
  EXPECT_EQ(m.not_finite, 2u);
  EXPECT_EQ(m.first_not_finite, 2u);
  EXPECT_NEAR(m.mean_deg, (0 + 180 + 180) / 3.0, 1e-9);
  EXPECT_EQ(m.error_deg.pixels[3], 180.0f);
  EXPECT_EQ(m.missing, 2u);
  ImageF nan(4, 1, 3);
  for (float& v : nan.pixels) v = std::numeric_limits<float>::quiet_NaN();
  try {
    CompareNormals(nan, gt, Mask(4, 1, true));
    FAIL() << "an estimate of NaN everywhere was scored";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "holds no finite normal where the ground truth has one (NaN or infinite at all 3 "
                 "such pixels; the first at column 0, row 0)");
  }
}

// A zero estimate is a missing normal (180°), counted; an estimate that is 0 wherever the ground
// truth has a normal (a blank map, the wrong file) is refused, not scored 180° with exit 0.
TEST(Metrics, AnEstimateWithNoNormalIsRefused) {
  ImageF gt(3, 1, 3), est(3, 1, 3);
  for (int i = 0; i < 3; ++i) gt.pixels[3 * i + 2] = 1;
  est.pixels[2] = 1;
  const AngularErrorMetrics m = CompareNormals(est, gt, Mask(3, 1, true));
  EXPECT_EQ(m.missing, 2u);
  EXPECT_EQ(m.not_finite, 0u);
  EXPECT_NEAR(m.mean_deg, 120.0, 1e-9);
  est.pixels[2] = 0;
  try {
    CompareNormals(est, gt, Mask(3, 1, true));
    FAIL() << "an estimate of 0 everywhere was scored";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "holds no normal where the ground truth has one (0 at all 3 such pixels)");
  }
  est.pixels[0] = std::numeric_limits<float>::quiet_NaN();
  try {
    CompareNormals(est, gt, Mask(3, 1, true));
    FAIL() << "an estimate of 0 and NaN was scored";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "holds no normal where the ground truth has one (0, NaN or infinite at all 3 such "
                 "pixels)");
  }
}

}  // namespace
}  // namespace iphong::solve
