// Renders with exact ground truth shared by the solver tests: spheres under hemisphere or ring
// lights, and two balls of different materials side by side.
#pragma once

#include <cmath>
#include <utility>
#include <vector>

#include "geometry/primitives.h"
#include "render/renderer.h"
#include "solve/normals.h"
#include "solve/photometric_data.h"

namespace iphong::solve::test_data {

struct Synthetic {
  render::Scene scene;
  render::RenderOutput out;
  PhotometricData data;
};

// A sphere under `lights` hemisphere lights (or a ring of them at 45° elevation), rendered per
// light (no ambient unless given) with the Phong lobe or `lobe`.
inline Synthetic MakeSphereData(const reflectance::Material& material, int lights,
                                double noise_sigma, const Vec3d& ambient = Vec3d::Zero(),
                                int size = 96, bool ring = false,
                                reflectance::Lobe lobe = reflectance::Lobe::kPhong) {
  Synthetic s;
  s.scene.camera = geometry::Camera::Orthographic(size, size, 2.0);
  s.scene.lighting.ambient = ambient;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < lights; ++i) {
    const double z = ring ? std::sqrt(0.5) : 1 - 0.5 * (i + 0.5) / lights, r = std::sqrt(1 - z * z),
                 a = ring ? 2 * M_PI * i / lights : golden * i;
    s.scene.lighting.lights.push_back(reflectance::Light::Directional(
        Vec3d(r * std::cos(a), r * std::sin(a), z), Vec3d(1.0, 0.9, 0.8)));
  }
  render::SceneObject sphere;
  sphere.mesh = geometry::MakeSphere(0.9, 6);
  sphere.material = material;
  s.scene.objects.push_back(sphere);
  render::RenderOptions options;
  options.model.lobe = lobe;
  options.noise.gaussian_sigma = noise_sigma;
  options.noise.seed = 3;
  s.out = render::Render(s.scene, options, true);
  std::vector<const float*> images;
  std::vector<Vec3d> dirs, intensities;
  for (std::size_t j = 0; j < s.out.per_light.size(); ++j) {
    images.push_back(s.out.per_light[j].pixels.data());
    dirs.push_back(s.scene.lighting.lights[j].direction_cam);
    intensities.push_back(s.scene.lighting.lights[j].diffuse_intensity);
  }
  s.data = GatherObservations(images, size, size, s.out.mask, dirs, intensities);
  return s;
}

// Two balls side by side (left at x = −1, right at x = 1) in a 160×80 view under 24 white
// hemisphere lights.
inline Synthetic MakeTwoBallsData(const reflectance::Material& left,
                                  const reflectance::Material& right) {
  Synthetic s;
  s.scene.camera = geometry::Camera::Orthographic(160, 80, 4.0);
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < 24; ++i) {
    const double z = 1 - 0.5 * (i + 0.5) / 24, r = std::sqrt(1 - z * z);
    s.scene.lighting.lights.push_back(reflectance::Light::Directional(
        Vec3d(r * std::cos(golden * i), r * std::sin(golden * i), z), Vec3d::Ones()));
  }
  for (const auto& [material, x] : {std::pair{left, -1.0}, std::pair{right, 1.0}}) {
    render::SceneObject ball;
    ball.mesh = geometry::MakeSphere(0.9, 5);
    geometry::TransformMesh(ball.mesh, Eigen::Affine3d(Eigen::Translation3d(x, 0, 0)));
    ball.material = material;
    s.scene.objects.push_back(ball);
  }
  s.out = render::Render(s.scene, render::RenderOptions{}, true);
  std::vector<const float*> images;
  std::vector<Vec3d> dirs;
  for (std::size_t j = 0; j < s.out.per_light.size(); ++j) {
    images.push_back(s.out.per_light[j].pixels.data());
    dirs.push_back(s.scene.lighting.lights[j].direction_cam);
  }
  s.data = GatherObservations(images, 160, 80, s.out.mask, dirs,
                              std::vector<Vec3d>(dirs.size(), Vec3d::Ones()));
  return s;
}

inline reflectance::Material Plastic() {
  reflectance::Material m;
  m.ka = Vec3d::Constant(0.02);
  m.kd = Vec3d(0.7, 0.5, 0.3);
  m.ks = Vec3d::Constant(0.4);
  m.shininess = 20;
  return m;
}

inline NormalOptions Known(const reflectance::Material& m, const Vec3d& ambient) {
  NormalOptions o;
  o.material_known = true;
  o.ambient_term = ambient.cwiseProduct(m.ka);
  o.ks = m.ks;
  o.shininess = m.shininess;
  return o;
}

}  // namespace iphong::solve::test_data
