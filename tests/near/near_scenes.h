// Near-light captures with exact ground truth for the near-light tests: an analytic sphere seen
// by a pinhole (or orthographic) camera, shaded per point light by the shared model, pixel by
// pixel (no mesh, no rasterizer: the exact sphere at every pixel centre).
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "geometry/height_map.h"
#include "reflectance/lighting.h"
#include "reflectance/material.h"
#include "solve/photometric_data.h"

namespace iphong::near::test_data {

struct NearScene {
  geometry::HeightMapFrame frame;
  int width = 160, height = 128;
  Vec3d center = Vec3d(0, 0, -500);  // mm
  double radius = 50;
  std::vector<reflectance::Light> lights;
  reflectance::Material material;
  reflectance::ModelOptions model;
  double noise_sigma = 0;
};

struct NearCapture {
  solve::PhotometricData data;  // point lights set, no surface points yet
  ImageF normal_gt;             // 3 channels, 0 outside
  ImageF depth_gt;              // 1 channel, 0 outside
};

// A dome of `count` LEDs (or isotropic lights) around `center` at `radius`, elevations 25°–75°
// above the plane facing the camera, aimed at the centre, intensity `power` (irradiance × mm²).
inline std::vector<reflectance::Light> Dome(const Vec3d& center, double radius, int count,
                                            double power, double anisotropy = 0) {
  std::vector<reflectance::Light> lights;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double elevation = (25 + 50.0 * (i + 0.5) / count) * M_PI / 180;
    const double azimuth = golden * i;
    const Vec3d dir(std::cos(elevation) * std::cos(azimuth),
                    std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    const Vec3d position = center + radius * dir;
    lights.push_back(reflectance::Light::Led(position, Vec3d::Constant(power), -dir, anisotropy));
  }
  return lights;
}

// Ray-traced at each pixel centre: the sphere's normal and point, each light's image by the
// shared model (reflectance::Shade with that light alone), Gaussian noise if asked.
inline NearCapture RenderNearSphere(const NearScene& s) {
  NearCapture c;
  c.normal_gt = ImageF(s.width, s.height, 3);
  c.depth_gt = ImageF(s.width, s.height, 1);
  Mask mask(s.width, s.height, false);
  std::vector<ImageF> images(s.lights.size(), ImageF(s.width, s.height, 3));
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, s.noise_sigma > 0 ? s.noise_sigma : 1);
  for (int row = 0; row < s.height; ++row) {
    for (int col = 0; col < s.width; ++col) {
      // The ray through the pixel centre: origin and unit direction.
      Vec3d origin, dir;
      if (s.frame.perspective) {
        origin = Vec3d::Zero();
        dir = geometry::HeightMapPoint(s.frame, s.width, s.height, col, row, 1).normalized();
      } else {
        origin = geometry::HeightMapPoint(s.frame, s.width, s.height, col, row, 0);
        dir = Vec3d(0, 0, -1);
      }
      const Vec3d oc = origin - s.center;
      const double b = oc.dot(dir), c2 = oc.squaredNorm() - s.radius * s.radius;
      const double disc = b * b - c2;
      if (disc <= 0) continue;
      const double t = -b - std::sqrt(disc);
      const Vec3d x = origin + t * dir;
      const Vec3d n = (x - s.center).normalized();
      const Vec3d v = -dir;
      if (n.dot(v) < 0.02) continue;  // grazing: a pixel straddling the outline
      const std::size_t p = static_cast<std::size_t>(row) * s.width + col;
      mask.inside[p] = 1;
      for (int k = 0; k < 3; ++k) c.normal_gt.pixels[3 * p + k] = static_cast<float>(n[k]);
      c.depth_gt.pixels[p] = static_cast<float>(-x.z());
      for (std::size_t j = 0; j < s.lights.size(); ++j) {
        reflectance::Lighting one;
        one.lights = {s.lights[j]};
        const Vec3d rgb = reflectance::Shade<double>(n, v, x, s.material, one, s.model);
        for (int k = 0; k < 3; ++k) {
          const double value = rgb[k] + (s.noise_sigma > 0 ? noise(rng) : 0.0);
          images[j].pixels[3 * p + k] = static_cast<float>(std::max(0.0, value));
        }
      }
    }
  }
  std::vector<const float*> ptrs;
  std::vector<Vec3d> dirs, intensities;
  for (std::size_t j = 0; j < s.lights.size(); ++j) {
    ptrs.push_back(images[j].pixels.data());
    dirs.push_back((s.lights[j].position_cam - s.center).normalized());
    intensities.push_back(s.lights[j].diffuse_intensity);
  }
  c.data = solve::GatherObservations(ptrs, s.width, s.height, mask, dirs, intensities);
  c.data.point_lights = s.lights;
  c.data.perspective = s.frame.perspective;
  return c;
}

}  // namespace iphong::near::test_data
