// The array API: same numbers as the templated core, masks, threads, and messages for bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "reflectance/shade.h"

namespace iphong::reflectance {
namespace {

struct Fixture {
  std::vector<double> normals, positions;
  Material material = FindMaterialPreset("jade").material;
  Lighting lighting;

  explicit Fixture(std::size_t count) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    for (std::size_t i = 0; i < count; ++i) {
      Vec3d n(u(rng), u(rng), std::abs(u(rng)) + 0.1);
      n *= 0.5 + std::abs(u(rng));  // not unit: the API normalizes
      for (int c = 0; c < 3; ++c) {
        normals.push_back(n[c]);
        positions.push_back(u(rng));
      }
    }
    lighting.ambient = Vec3d(0.5, 0.5, 0.5);
    lighting.lights = {Light::Directional(Vec3d(0.3, 0.4, 0.866), Vec3d(1, 0.9, 0.8)),
                       Light::Point(Vec3d(0, 0, 3), Vec3d(4, 4, 4), true)};
  }
  PointsView<double> View(const double* view) const {
    PointsView<double> p;
    p.normals_cam = normals.data();
    p.count = normals.size() / 3;
    p.views_cam = view;
    p.positions_cam = positions.data();
    return p;
  }
};

TEST(ShadePoints, MatchesTemplatedCorePointByPoint) {
  Fixture f(500);
  const double view[3] = {0, 0, 1};
  std::vector<double> out(f.normals.size());
  ShadePoints(f.View(view), f.material, f.lighting, ModelOptions{}, out.data());
  for (std::size_t i = 0; i < 500; ++i) {
    const Vec3d n =
        Vec3d(f.normals[3 * i], f.normals[3 * i + 1], f.normals[3 * i + 2]).normalized();
    const Vec3d p(f.positions[3 * i], f.positions[3 * i + 1], f.positions[3 * i + 2]);
    const Vec3d expected = Shade(n, Vec3d(0, 0, 1), p, f.material, f.lighting, ModelOptions{});
    for (int c = 0; c < 3; ++c) ASSERT_DOUBLE_EQ(out[3 * i + c], expected[c]);
  }
}

TEST(ShadePoints, ThreadedEqualsSingleThreaded) {
  Fixture f(200000);
  const double view[3] = {0.1, 0, 1};
  std::vector<double> one(f.normals.size()), many(f.normals.size());
  ShadePoints(f.View(view), f.material, f.lighting, ModelOptions{}, one.data(), 1);
  ShadePoints(f.View(view), f.material, f.lighting, ModelOptions{}, many.data(), 4);
  EXPECT_EQ(one, many);
}

TEST(ShadePoints, MaskedPointsAreZeroAndMayHoldZeroNormals) {
  Fixture f(4);
  for (int c = 0; c < 3; ++c) f.normals[3 + c] = 0;  // point 1: background, zero normal
  const unsigned char mask[4] = {1, 0, 1, 1};
  const double view[3] = {0, 0, 1};
  auto points = f.View(view);
  points.mask = mask;
  std::vector<double> out(12, -1.0);
  ShadePoints(points, f.material, f.lighting, ModelOptions{}, out.data());
  EXPECT_EQ(out[3], 0.0);
  EXPECT_EQ(out[4], 0.0);
  EXPECT_EQ(out[5], 0.0);
  EXPECT_GT(out[0], 0.0);
}

TEST(ShadePoints, BadInputGivesMessagesNamingThePoint) {
  Fixture f(3);
  const double view[3] = {0, 0, 1};
  std::vector<double> out(9);
  auto expect_message = [&](const PointsView<double>& points, const std::string& fragment) {
    try {
      ShadePoints(points, f.material, f.lighting, ModelOptions{}, out.data());
      ADD_FAILURE() << "expected an error containing '" << fragment << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  auto zero = f;
  zero.normals[6] = zero.normals[7] = zero.normals[8] = 0;
  expect_message(zero.View(view), "normal 2");
  auto nan = f;
  nan.normals[1] = std::nan("");
  expect_message(nan.View(view), "normal 0");
  const double bad_view[3] = {0, 0, 0};
  expect_message(f.View(bad_view), "view 0");
  auto no_positions = f.View(view);
  no_positions.positions_cam = nullptr;
  expect_message(no_positions, "point lights need surface positions");
  auto wrong_views = f.View(view);
  wrong_views.view_count = 2;
  expect_message(wrong_views, "expected one view or one per normal");
}

TEST(ShadePoints, FloatStorageAgreesWithDouble) {
  Fixture f(100);
  std::vector<float> normals(f.normals.begin(), f.normals.end());
  std::vector<float> positions(f.positions.begin(), f.positions.end());
  const float view_f[3] = {0, 0, 1};
  const double view_d[3] = {0, 0, 1};
  PointsView<float> pf;
  pf.normals_cam = normals.data();
  pf.count = 100;
  pf.views_cam = view_f;
  pf.positions_cam = positions.data();
  std::vector<float> out_f(300);
  std::vector<double> out_d(300);
  ShadePoints(pf, f.material, f.lighting, ModelOptions{}, out_f.data());
  ShadePoints(f.View(view_d), f.material, f.lighting, ModelOptions{}, out_d.data());
  for (int i = 0; i < 300; ++i) EXPECT_NEAR(out_f[i], out_d[i], 1e-5 * (1 + out_d[i]));
}

}  // namespace
}  // namespace iphong::reflectance
