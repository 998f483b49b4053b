// The SPEC frame: pixel centres, y up, row 0 at the top; analytic sphere samples.
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/analytic.h"

namespace iphong::geometry {
namespace {

TEST(Camera, PixelCentresAndYUp) {
  Camera camera;
  camera.width = 4;
  camera.height = 2;
  camera.extent = 2.0;  // x ∈ [−1, 1], y ∈ [−0.5, 0.5], pixel size 0.5
  EXPECT_DOUBLE_EQ(camera.x_of_col(0), -0.75);
  EXPECT_DOUBLE_EQ(camera.x_of_col(3), 0.75);
  EXPECT_DOUBLE_EQ(camera.y_of_row(0), 0.25);  // the top row has the largest y
  EXPECT_DOUBLE_EQ(camera.y_of_row(1), -0.25);
  EXPECT_EQ(camera.view_cam(), Vec3d(0, 0, 1));
  camera.extent = 0;
  EXPECT_NE(camera.Validate(), "");
}

TEST(SampleSphere, UnitNormalsPointOutwardInTheSpecFrame) {
  Camera camera;
  camera.width = camera.height = 64;
  const SurfaceMap map = SampleSphere(camera, Vec3d::Zero(), 0.8);
  // Area: π r² / pixel area, to within the boundary pixels.
  const double expected = M_PI * 0.8 * 0.8 / std::pow(camera.pixel_size(), 2);
  EXPECT_NEAR(static_cast<double>(map.mask.count()), expected,
              2 * M_PI * 0.8 / camera.pixel_size());
  for (int row = 0; row < 64; ++row) {
    for (int col = 0; col < 64; ++col) {
      if (!map.mask.at(col, row)) continue;
      const float* n = map.normal_cam.at(col, row);
      const float* p = map.position_cam.at(col, row);
      EXPECT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-6);
      EXPECT_GT(n[2], 0.0f);
      EXPECT_NEAR(p[0], camera.x_of_col(col), 1e-6);
      EXPECT_NEAR(p[1], camera.y_of_row(row), 1e-6);
    }
  }
  // Top of the image (row 0 side) faces up (+y), left side faces −x.
  EXPECT_GT(map.normal_cam.at(32, 8)[1], 0.5f);
  EXPECT_LT(map.normal_cam.at(8, 32)[0], -0.5f);
}

TEST(SampleSphere, RejectsBadArguments) {
  Camera camera;
  EXPECT_THROW(SampleSphere(camera, Vec3d::Zero(), 0.0), std::invalid_argument);
  EXPECT_THROW(SampleSphere(camera, Vec3d(0, NAN, 0), 1.0), std::invalid_argument);
  camera.width = 0;
  EXPECT_THROW(SampleSphere(camera, Vec3d::Zero(), 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace iphong::geometry
