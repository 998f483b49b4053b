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

// A 201×201 analytic sphere under one light; returns the normal at the brightest pixel of
// `channel` and that pixel.
struct Peak {
  Vec3d normal;
  Brightest pixel;
  float background;
};

Peak ShadeSphere(const reflectance::Material& m, const Vec3d& light,
                 const reflectance::ModelOptions& options, int channel) {
  const geometry::Camera camera = geometry::Camera::Orthographic(201, 201, 2.0);
  const auto sphere = geometry::SampleSphere(camera, Vec3d::Zero(), 0.9);
  reflectance::Lighting lighting;
  lighting.lights = {Light::Directional(light, Vec3d::Ones())};
  const ImageF image = ShadeSurfaceMap(sphere, camera, m, lighting, options);
  const Brightest b = FindBrightest(image, channel);
  const float* n = sphere.normal_cam.at(b.col, b.row);
  return {Vec3d(n[0], n[1], n[2]), b, image.at(0, 0)[channel]};
}

TEST(ShadeSurfaceMap, LambertPeakWhereNormalEqualsLight) {
  reflectance::Material m;
  m.kd = Vec3d::Ones();
  reflectance::ModelOptions lambert;
  lambert.lobe = reflectance::Lobe::kLambert;
  const Vec3d light = Vec3d(0.3, 0.4, 0.866).normalized();
  const Peak peak = ShadeSphere(m, light, lambert, 0);
  EXPECT_GT(peak.normal.dot(light), std::cos(0.02));
  EXPECT_NEAR(peak.pixel.value, 1.0, 1e-3);
  EXPECT_EQ(peak.background, 0.0f);
}

TEST(ShadeSurfaceMap, PhongHighlightAtTheHalfwayNormal) {
  // Orthographic view V = z: the highlight peak is where R = V, i.e. N ∥ (L + V).
  reflectance::Material m;
  m.ks = Vec3d::Ones();
  m.shininess = 50;
  const Vec3d light = Vec3d(-0.5, 0.3, 0.8).normalized();
  const Peak peak = ShadeSphere(m, light, reflectance::ModelOptions{}, 1);
  EXPECT_GT(peak.normal.dot((light + Vec3d(0, 0, 1)).normalized()), std::cos(0.02));
  EXPECT_LT(peak.pixel.col, 100);  // light from the left ...
  EXPECT_LT(peak.pixel.row, 100);  // ... and from above (y up, row 0 at the top)
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
