// The local fit's censoring rounds on single pixels with a known normal: a round whose
// censoring leaves the weights as they were ends the fit, unless it ran out of iterations.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "solve/pixel_fit.h"

namespace iphong::solve {
namespace {

constexpr int kLights = 24;

// Lights on a cone of 20–50° round the view, so every normal within 30° of it sees each of them
// at N·L > 0.3: nothing in shadow.
std::vector<Vec3d> Lights() {
  std::vector<Vec3d> lights;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int j = 0; j < kLights; ++j) {
    const double polar = (20 + 30.0 * j / (kLights - 1)) * M_PI / 180;
    lights.emplace_back(std::sin(polar) * std::cos(golden * j),
                        std::sin(polar) * std::sin(golden * j), std::cos(polar));
  }
  return lights;
}

// One pixel of kd·(N·L) + ks·(N·H)^20 (Blinn-Phong, white lights) with Gaussian noise of σ = 0.005:
// every residual far above the censoring threshold, a tenth of the pixel's brightness.
PhotometricData OnePixel(const Vec3d& normal, std::mt19937& rng) {
  std::normal_distribution<double> noise(0, 0.005);
  PhotometricData d;
  d.width = d.height = 1;
  d.images = kLights;
  d.pixels = {0};
  d.light_directions = Lights();
  for (const Vec3d& l : d.light_directions) {
    d.light_intensities.push_back(Vec3d::Ones());
    const double lobe = std::pow(normal.dot((l + Vec3d::UnitZ()).normalized()), 20);
    for (int c = 0; c < 3; ++c) {
      d.values.push_back(static_cast<float>(0.6 * normal.dot(l) + 0.3 * lobe + noise(rng)));
    }
  }
  return d;
}

internal::PixelSolution Fit(const PhotometricData& data, const Vec3d& start, int rounds,
                            int max_iterations = 10) {
  PixelFitSettings settings;
  settings.model.lobe = reflectance::Lobe::kBlinnPhong;
  settings.shininess = 20;
  settings.rounds = rounds;
  settings.max_iterations = max_iterations;
  PixelFitter fitter(data, settings);
  EXPECT_TRUE(fitter.Prepare(0));
  internal::PixelSolution s;
  s.normal = start;
  fitter.Fit(s);
  return s;
}

double AngleDeg(const Vec3d& a, const Vec3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI;
}

TEST(PixelFit, WeightsLeftAsTheyWereEndTheFit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 40; ++i) {
    const Vec3d truth = Vec3d(0.4 * u(rng), 0.4 * u(rng), 1).normalized();
    const Vec3d start = (truth + Vec3d(0.05 * u(rng), 0.05 * u(rng), 0)).normalized();
    const PhotometricData data = OnePixel(truth, rng);
    ASSERT_EQ(data.Validate(), "");
    // Nothing is censored, before or after any round: one round is the whole fit.
    const internal::PixelSolution one = Fit(data, start, 1), four = Fit(data, start, 4);
    EXPECT_LT(AngleDeg(one.normal, truth), 1.0) << "pixel " << i;
    EXPECT_EQ(four.iterations, one.iterations) << "pixel " << i;
    EXPECT_EQ(four.normal, one.normal) << "pixel " << i;  // bit for bit: no second round ran
    EXPECT_EQ(four.albedo, one.albedo) << "pixel " << i;
  }
}

TEST(PixelFit, ARoundOutOfIterationsIsContinued) {
  std::mt19937 rng(11);
  const Vec3d truth = Vec3d(0.3, -0.2, 0.9).normalized();
  const Vec3d start = Vec3d(0.26, -0.12, 0.9).normalized();  // 5° off: nothing censored
  const PhotometricData data = OnePixel(truth, rng);
  // One iteration a round: the weights do not change, yet each round takes the fit further.
  const internal::PixelSolution one = Fit(data, start, 1, 1), four = Fit(data, start, 4, 1);
  EXPECT_EQ(one.iterations, 1);
  EXPECT_GT(four.iterations, 1);
  EXPECT_LT(AngleDeg(four.normal, truth), AngleDeg(one.normal, truth));
}

}  // namespace
}  // namespace iphong::solve
