// Seed 003's inverse example: one light, two solutions per profile pixel, priors pick the truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "geometry/primitives.h"
#include "render/renderer.h"
#include "solve/few_images.h"
#include "solve/metrics.h"

namespace iphong::solve {
namespace {

using reflectance::Light;

TEST(ProfileNormals, SeedThreeCylinderExampleHasTwoSolutions) {
  // L = [0.71, 0.71]: (I − Ca)/Cd = 0.71 Nx + 0.71 Nz and Nx² + Nz² = 1.
  const Eigen::Vector2d light(0.71, 0.71);
  const Eigen::Vector2d l = light.normalized();
  for (double theta_deg : {-60.0, -20.0, 0.0, 10.0, 45.0, 80.0}) {
    const double t = theta_deg * M_PI / 180;
    const Eigen::Vector2d truth(std::sin(t), std::cos(t));  // a cylinder's profile normal
    const double shading = truth.dot(l);
    const auto solutions = ProfileNormals(shading, light);
    for (const auto& n : solutions) {
      EXPECT_NEAR(n.norm(), 1.0, 1e-12);
      EXPECT_NEAR(n.dot(l), shading, 1e-12);  // both explain the pixel exactly
    }
    // The two solutions are the truth and its mirror image about L (one and the same at 45°).
    const Eigen::Vector2d mirror = 2 * shading * l - truth;
    const auto near = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      return (a - b).norm() < 1e-12;
    };
    EXPECT_TRUE((near(solutions[0], truth) && near(solutions[1], mirror)) ||
                (near(solutions[0], mirror) && near(solutions[1], truth)))
        << "theta " << theta_deg;
  }
  // Facing the light: a single (double) solution.
  const auto touching = ProfileNormals(1.0, light);
  EXPECT_LT((touching[0] - touching[1]).norm(), 1e-12);
  EXPECT_THROW(ProfileNormals(1.5, light), std::invalid_argument);
}

// A Lambertian object with a known albedo, rendered once per light and solved from those images.
struct FewImageCase {
  render::RenderOutput out;
  FewImageResult result;
};

FewImageCase RenderAndSolve(int width, int height, const std::vector<Vec3d>& light_dirs,
                            geometry::TriangleMesh mesh, const Vec3d& kd,
                            std::function<void(double)> progress = {}) {
  render::Scene scene;
  scene.camera = geometry::Camera::Orthographic(width, height, 2.0);
  for (const Vec3d& d : light_dirs)
    scene.lighting.lights.push_back(Light::Directional(d, Vec3d::Ones()));
  render::SceneObject object;
  object.mesh = std::move(mesh);
  object.material.kd = kd;
  scene.objects.push_back(std::move(object));
  FewImageCase c;
  c.out = render::Render(scene, render::RenderOptions{}, true);
  std::vector<const float*> images;
  std::vector<Vec3d> dirs, intensities;
  for (std::size_t j = 0; j < c.out.per_light.size(); ++j) {
    images.push_back(c.out.per_light[j].pixels.data());
    dirs.push_back(scene.lighting.lights[j].direction_cam);
    intensities.push_back(scene.lighting.lights[j].diffuse_intensity);
  }
  FewImageOptions o;
  o.material.kd = kd;
  o.progress = std::move(progress);
  c.result = EstimateNormalsFewImages(
      GatherObservations(images, width, height, c.out.mask, dirs, intensities), o);
  return c;
}

TEST(FewImages, CylinderWithOneLightPriorsPickTheTrueSolution) {
  // Seed 003's finger: a cylinder along y, one light at 45° in the x-z plane, Lambertian with a
  // known albedo. The cylinder runs past the top and bottom of the image, so its only occluding
  // contours are left and right.
  const FewImageCase c =
      RenderAndSolve(64, 48, {Vec3d(0.71, 0, 0.71)}, geometry::MakeCylinder(0.8, 3.0, 256, false),
                     Vec3d::Constant(0.8));
  const render::RenderOutput& out = c.out;
  const FewImageResult& r = c.result;
  // Where the light reaches (N·L > 0.05), compare with the truth and with the mirror solution.
  int total = 0, true_branch = 0;
  double error_sum = 0;
  const Vec3d l = Vec3d(0.71, 0, 0.71).normalized();
  for (std::size_t p = 0; p < out.mask.inside.size(); ++p) {
    if (!out.mask.inside[p]) continue;
    const Vec3d truth(out.normal_cam.pixels[3 * p], out.normal_cam.pixels[3 * p + 1],
                      out.normal_cam.pixels[3 * p + 2]);
    if (truth.dot(l) < 0.05) continue;
    const Vec3d n(r.normals.pixels[3 * p], r.normals.pixels[3 * p + 1],
                  r.normals.pixels[3 * p + 2]);
    const Vec3d mirror = 2 * truth.dot(l) * l - truth;
    const double to_truth = std::acos(std::clamp(n.dot(truth), -1.0, 1.0));
    const double to_mirror = std::acos(std::clamp(n.dot(mirror), -1.0, 1.0));
    ++total;
    true_branch += to_truth < to_mirror || (truth - mirror).norm() < 0.05;
    error_sum += to_truth * 180 / M_PI;
  }
  ASSERT_GT(total, 500);
  const double mean = error_sum / total;
  RecordProperty("mean_error_deg", std::to_string(mean));
  std::printf("cylinder, one light: %.1f%% of lit pixels on the true branch, mean error %.2f deg\n",
              100.0 * true_branch / total, mean);
  EXPECT_GT(static_cast<double>(true_branch) / total, 0.95);
  EXPECT_LT(mean, 5.0);
  // The ambiguity map: the data alone allows a cone of opening 2·acos(N·L).
  const std::size_t centre = 24 * 64 + 32;
  const Vec3d truth(out.normal_cam.pixels[3 * centre], out.normal_cam.pixels[3 * centre + 1],
                    out.normal_cam.pixels[3 * centre + 2]);
  EXPECT_NEAR(r.ambiguity_deg.pixels[centre], 2 * std::acos(truth.dot(l)) * 180 / M_PI, 0.5);
}

TEST(FewImages, SphereFromTwoImages) {
  const FewImageCase c = RenderAndSolve(48, 48, {Vec3d(0.5, 0.3, 0.8), Vec3d(-0.4, -0.2, 0.9)},
                                        geometry::MakeSphere(0.85, 5), Vec3d(0.6, 0.5, 0.4));
  const AngularErrorMetrics e = CompareNormals(c.result.normals, c.out.normal_cam, c.out.mask);
  std::printf("sphere, two lights: mean %.2f deg, median %.2f deg\n", e.mean_deg, e.median_deg);
  EXPECT_LT(e.median_deg, 3.0);
  EXPECT_LT(e.mean_deg, 6.0);
}

TEST(FewImages, ReportsProgressThroughBothStages) {
  // One- and two-image runs on camera-sized photos take minutes: they must show progress.
  std::vector<double> reported;
  RenderAndSolve(32, 32, {Vec3d(0.5, 0.3, 0.8), Vec3d(-0.4, -0.2, 0.9)},
                 geometry::MakeSphere(0.85, 4), Vec3d(0.6, 0.5, 0.4),
                 [&](double f) { reported.push_back(f); });
  ASSERT_GE(reported.size(), 3u);
  EXPECT_GT(reported.front(), 0.0);
  EXPECT_LE(reported.front(), 0.2);  // the priors' stage first
  for (std::size_t i = 1; i < reported.size(); ++i) EXPECT_GE(reported[i], reported[i - 1]);
  EXPECT_EQ(reported.back(), 1.0);
  EXPECT_GT(*std::upper_bound(reported.begin(), reported.end(), 0.2), 0.2);  // the data stage
}

TEST(FewImages, RequiresAKnownAlbedoAndAtMostTwoImages) {
  PhotometricData d;
  d.width = d.height = 2;
  d.images = 1;
  d.pixels = {0};
  d.values = {0.5f, 0.5f, 0.5f};
  d.light_directions = {Vec3d(0, 0, 1)};
  d.light_intensities = {Vec3d::Ones()};
  FewImageOptions o;
  EXPECT_THROW(EstimateNormalsFewImages(d, o), std::invalid_argument);  // kd unknown (0)
  o.material.kd = Vec3d::Constant(0.5);
  EXPECT_NO_THROW(EstimateNormalsFewImages(d, o));
}

}  // namespace
}  // namespace iphong::solve
