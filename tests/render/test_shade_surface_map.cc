// Per-pixel shading of an analytic sphere: the brightest pixels sit where the model says.
#include <gtest/gtest.h>

#include <cmath>

#include "render/shade_normal_map.h"

namespace iphong::render {
namespace {

using reflectance::Light;

struct Brightest {
  int col = -1, row = -1;
  float value = -1;
};

Brightest FindBrightest(const ImageF& image, int channel) {
  Brightest b;
  for (int row = 0; row < image.height; ++row) {
    for (int col = 0; col < image.width; ++col) {
      if (image.at(col, row)[channel] > b.value) b = {col, row, image.at(col, row)[channel]};
    }
  }
  return b;
}

TEST(ShadeSurfaceMap, LambertPeakWhereNormalEqualsLight) {
  geometry::Camera camera;
  camera.width = camera.height = 201;
  const auto sphere = geometry::SampleSphere(camera, Vec3d::Zero(), 0.9);
  reflectance::Material m;
  m.kd = Vec3d::Ones();
  reflectance::Lighting lighting;
  const Vec3d light = Vec3d(0.3, 0.4, 0.866).normalized();
  lighting.lights = {Light::Directional(light, Vec3d::Ones())};
  reflectance::ModelOptions lambert;
  lambert.lobe = reflectance::Lobe::kLambert;
  const ImageF image = ShadeSurfaceMap(sphere, camera, m, lighting, lambert);
  const Brightest b = FindBrightest(image, 0);
  const float* n = sphere.normal_cam.at(b.col, b.row);
  EXPECT_GT(Vec3d(n[0], n[1], n[2]).dot(light), std::cos(0.02));
  EXPECT_NEAR(b.value, 1.0, 1e-3);
  EXPECT_EQ(image.at(0, 0)[0], 0.0f);  // background
}

TEST(ShadeSurfaceMap, PhongHighlightAtTheHalfwayNormal) {
  // Orthographic view V = z: the highlight peak is where R = V, i.e. N ∥ (L + V).
  geometry::Camera camera;
  camera.width = camera.height = 201;
  const auto sphere = geometry::SampleSphere(camera, Vec3d::Zero(), 0.9);
  reflectance::Material m;
  m.ks = Vec3d::Ones();
  m.shininess = 50;
  reflectance::Lighting lighting;
  const Vec3d light = Vec3d(-0.5, 0.3, 0.8).normalized();
  lighting.lights = {Light::Directional(light, Vec3d::Ones())};
  const ImageF image = ShadeSurfaceMap(sphere, camera, m, lighting, reflectance::ModelOptions{});
  const Brightest b = FindBrightest(image, 1);
  const float* n = sphere.normal_cam.at(b.col, b.row);
  const Vec3d half = (light + Vec3d(0, 0, 1)).normalized();
  EXPECT_GT(Vec3d(n[0], n[1], n[2]).dot(half), std::cos(0.02));
  EXPECT_LT(b.col, 100);  // light from the left ...
  EXPECT_LT(b.row, 100);  // ... and from above (y up, row 0 at the top)
}

TEST(ShadeSurfaceMap, SizeMismatchIsAnError) {
  geometry::Camera camera;
  camera.width = camera.height = 8;
  auto sphere = geometry::SampleSphere(camera, Vec3d::Zero(), 0.5);
  sphere.mask = Mask(4, 4, true);
  EXPECT_THROW(ShadeSurfaceMap(sphere, camera, reflectance::Material{}, reflectance::Lighting{},
                               reflectance::ModelOptions{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace iphong::render
