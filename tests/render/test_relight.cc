// Relighting's coverage: which pixels any light reaches, on an analytic hemisphere of normals.
#include <gtest/gtest.h>

#include <cmath>

#include "render/relight.h"

namespace iphong::render {
namespace {

TEST(Relight, LitPixelsCountsWhereSomeLightReaches) {
  // A hemisphere's normals over a 40×40 map (0 outside the disc), all facing the camera.
  const int size = 40;
  ImageF normals(size, size, 3), albedo(size, size, 3, 0.5f);
  std::size_t disc = 0, right = 0;
  for (int row = 0; row < size; ++row) {
    for (int col = 0; col < size; ++col) {
      const double x = (col + 0.5) / size * 2 - 1, y = 1 - (row + 0.5) / size * 2;
      if (x * x + y * y >= 0.9) continue;
      float* n = normals.at(col, row);
      n[0] = static_cast<float>(x), n[1] = static_cast<float>(y);
      n[2] = static_cast<float>(std::sqrt(1 - x * x - y * y));
      ++disc;
      right += x > 0;
    }
  }
  RelightInput input;
  input.normals_cam = &normals;
  input.albedo = &albedo;
  input.lights = {reflectance::Light::Directional(Vec3d(0, 0, -1), Vec3d::Ones())};
  RelightCoverage c = LitPixels(input);
  EXPECT_EQ(c.surface, disc);
  EXPECT_EQ(c.lit, 0u);  // behind every normal that faces the camera
  input.lights = {reflectance::Light::Directional(Vec3d(1, 0, 0), Vec3d::Ones())};
  EXPECT_EQ(LitPixels(input).lit, right);  // the right half: N·L = x > 0
  input.lights.push_back(reflectance::Light::Directional(Vec3d(0, 0, 1), Vec3d::Ones()));
  EXPECT_EQ(LitPixels(input).lit, disc);  // each pixel counted once
  EXPECT_EQ(LightsBehindNote(input), "");
  input.lights = {reflectance::Light::Directional(Vec3d(0, 0, -1), Vec3d::Ones())};
  EXPECT_EQ(LightsBehindNote(input),
            "the light lights 0 of " + std::to_string(disc) +
                " pixels (N.L > 0): it is behind the surface. A light direction points from the "
                "surface toward the light (x right, y up, z toward the camera)");
  // A light from the side, 1° behind the image plane, still lights about half the hemisphere
  // (N·L > 0 where x > 0.0175 z): a rim light, not a mistake, and nothing is said.
  input.lights = {reflectance::Light::Directional(Vec3d(1, 0, -0.0175), Vec3d::Ones())};
  EXPECT_GT(LitPixels(input).lit, disc / 3);
  EXPECT_EQ(LightsBehindNote(input), "");
  // Normals of another shape are Validate's to refuse; nothing is counted.
  ImageF flat(size, size, 1, 1.0f);
  input.normals_cam = &flat;
  EXPECT_EQ(LitPixels(input).surface, 0u);
}

}  // namespace
}  // namespace iphong::render
