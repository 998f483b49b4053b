// The lobes' powers taken in one batch (ConstantPowers, ShadingFactorsOfLights) against the
// model's one-light-at-a-time ShadingFactors: equal values and Jet derivatives to ~1e-13, for
// every lobe, and a value's power independent of its place in the batch.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "reflectance/phong.h"
#include "reflectance/powers.h"

namespace iphong::reflectance {
namespace {

using Jet2 = ceres::Jet<double, 2>;

TEST(ConstantPowers, AgreeWithExpOfScaledLog) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-14, 0);
  std::vector<double> base(1001), out(base.size());
  for (double& b : base) b = std::exp(u(rng));  // 8e-7 … 1
  base[0] = 1.0;
  for (const double n : {0.3, 5.5, 28.8, 300.7}) {
    ConstantPowers(base.data(), base.size(), n, out.data());
    for (std::size_t i = 0; i < base.size(); ++i) {
      // A few units in the last place of n·log x, which exp turns into a relative error.
      const double exponent = n * std::log(base[i]), expected = std::exp(exponent);
      ASSERT_NEAR(out[i], expected, 1e-15 * (1 + std::abs(exponent)) * expected)
          << base[i] << "^" << n;
    }
  }
}

TEST(ConstantPowers, AValueIsTheSameWhereverItSits) {
  const double x = 0.8372911, n = 28.8;
  double alone = 0;
  ConstantPowers(&x, 1, n, &alone);
  for (std::size_t count = 1; count <= 9; ++count) {
    for (std::size_t at = 0; at < count; ++at) {
      std::vector<double> base(count, 0.5), out(count);
      base[at] = x;
      ConstantPowers(base.data(), count, n, out.data());
      EXPECT_EQ(out[at], alone) << "at " << at << " of " << count;
    }
  }
  // In place, as the model's batch takes it.
  double in_place = x;
  ConstantPowers(&in_place, 1, n, &in_place);
  EXPECT_EQ(in_place, alone);
}

void ExpectNear(const Jet2& batch, const Jet2& one, const char* what, int j) {
  const double scale = 1e-13 * (std::abs(one.a) + std::abs(one.v[0]) + std::abs(one.v[1])) + 1e-300;
  EXPECT_NEAR(batch.a, one.a, scale) << what << ", light " << j;
  EXPECT_NEAR(batch.v[0], one.v[0], scale) << what << ", light " << j;
  EXPECT_NEAR(batch.v[1], one.v[1], scale) << what << ", light " << j;
}

TEST(ShadingFactorsOfLights, EqualShadingFactorsLightByLight) {
  std::mt19937 rng(9);
  std::normal_distribution<double> g(0, 1);
  // 60 lights over the whole sphere: some behind the surface, some beyond the lobe.
  std::vector<Vec3d> lights(60);
  for (Vec3d& l : lights) l = Vec3d(g(rng), g(rng), g(rng)).normalized();
  const Vec3d view = Vec3d(0.1, -0.05, 1).normalized();
  for (const Lobe lobe :
       {Lobe::kPhong, Lobe::kBlinnPhong, Lobe::kNormalCentred, Lobe::kLambert, Lobe::kOrenNayar}) {
    for (const double n : {28.8, 20.0, 0.7}) {
      for (const PowerMode power : {PowerMode::kExact, PowerMode::kFastApprox}) {
        ModelOptions options;
        options.lobe = lobe;
        options.power = power;
        for (int trial = 0; trial < 20; ++trial) {
          // A normal on a chart, as the local fit holds it: Jets in two coordinates.
          const Vec3d n0 = Vec3d(0.3 * g(rng), 0.3 * g(rng), 1).normalized();
          const Vec3d t1 = n0.cross(Vec3d::UnitX()).normalized(), t2 = n0.cross(t1);
          const Jet2 x0(0.1 * g(rng), 0), x1(0.1 * g(rng), 1);
          const Vec3T<Jet2> raw = n0.cast<Jet2>() + x0 * t1 + x1 * t2;
          const Vec3T<Jet2> normal = raw / raw.norm();
          std::vector<LightFactors<Jet2>> batch(lights.size());
          const Jet2 untouched(-7.0, 0);
          for (auto& f : batch) f.diffuse = f.specular = untouched;
          LobeScratch<Jet2> scratch;
          ShadingFactorsOfLights<Jet2, double>(
              normal, view, lights.data(), static_cast<int>(lights.size()), n, options,
              [](int j) { return j % 7 != 3; }, scratch, batch.data());
          for (std::size_t j = 0; j < lights.size(); ++j) {
            if (j % 7 == 3) {
              EXPECT_EQ(batch[j].diffuse.a, untouched.a);  // not used: left as it was
              EXPECT_EQ(batch[j].specular.a, untouched.a);
              continue;
            }
            const LightFactors<Jet2> one =
                ShadingFactors<Jet2, double>(normal, view, lights[j], Jet2(n), options);
            ExpectNear(batch[j].diffuse, one.diffuse, "diffuse", static_cast<int>(j));
            ExpectNear(batch[j].specular, one.specular, "specular", static_cast<int>(j));
          }
        }
      }
    }
  }
}

TEST(ShadingFactorsOfLights, IntegerShininessIsLightByLightBitForBit) {
  const Vec3d view(0, 0, 1), normal_d = Vec3d(0.2, 0.1, 1).normalized();
  std::vector<Vec3d> lights = {Vec3d(0.3, 0.2, 1).normalized(), Vec3d(-0.4, 0.1, 1).normalized()};
  ModelOptions options;
  options.lobe = Lobe::kBlinnPhong;
  std::vector<LightFactors<double>> batch(2);
  LobeScratch<double> scratch;
  ShadingFactorsOfLights<double, double>(
      normal_d, view, lights.data(), 2, 20.0, options, [](int) { return true; }, scratch,
      batch.data());
  for (int j = 0; j < 2; ++j) {
    const LightFactors<double> one =
        ShadingFactors<double>(normal_d, view, lights[j], 20.0, options);
    EXPECT_EQ(batch[j].diffuse, one.diffuse);
    EXPECT_EQ(batch[j].specular, one.specular);
  }
}

}  // namespace
}  // namespace iphong::reflectance
