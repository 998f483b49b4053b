// The closed-form elimination of kd (and of the specular scale σ) against a direct weighted least
// squares over the same unknowns, solved by QR.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <random>

#include "solve/internal.h"

namespace iphong::solve {
namespace {

struct Problem {
  std::vector<reflectance::LightFactors<double>> factors;
  std::vector<double> weight, y;  // y: K × 3
  Vec3d ks;
};

Problem MakeProblem(int k, const Vec3d& kd, const Vec3d& ks, double sigma, double noise,
                    unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n(0, noise);
  Problem p;
  p.ks = ks;
  for (int j = 0; j < k; ++j) {
    const double d = u(rng) < 0.2 ? 0.0 : u(rng);  // some lights in attached shadow
    const double s = d > 0 ? std::pow(u(rng), 8) : 0.0;
    p.factors.push_back({d, s});
    p.weight.push_back(u(rng) < 0.1 ? 0.0 : 0.2 + u(rng));
    for (int c = 0; c < 3; ++c) p.y.push_back(kd[c] * d + sigma * ks[c] * s + n(rng));
  }
  return p;
}

// min Σ_j w_j Σ_c (y_jc − kd_c d_j − σ ks_c s_j)² + λ Σ_c ks_c² (σ − 1)² over (kd, σ), or over kd
// alone with σ = 1.
Eigen::VectorXd DirectLeastSquares(const Problem& p, bool free_sigma, double prior) {
  const int k = static_cast<int>(p.factors.size()), unknowns = free_sigma ? 4 : 3;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * k + 1, unknowns);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(3 * k + 1);
  for (int j = 0; j < k; ++j) {
    const double root_w = std::sqrt(p.weight[j]);
    for (int c = 0; c < 3; ++c) {
      a(3 * j + c, c) = root_w * p.factors[j].diffuse;
      if (free_sigma) {
        a(3 * j + c, 3) = root_w * p.ks[c] * p.factors[j].specular;
        b(3 * j + c) = root_w * p.y[3 * j + c];
      } else {
        b(3 * j + c) = root_w * (p.y[3 * j + c] - p.ks[c] * p.factors[j].specular);
      }
    }
  }
  if (free_sigma) {
    const double root_prior = std::sqrt(prior * p.ks.squaredNorm());
    a(3 * k, 3) = root_prior;
    b(3 * k) = root_prior;
  }
  return a.colPivHouseholderQr().solve(b);
}

std::array<double, 3> Eliminate(const Problem& p, double* sigma, double prior) {
  return internal::EliminatedAlbedo<double>(
      p.factors, 3, [&](int c) { return p.ks[c]; },
      [&](std::size_t j, int c) { return p.y[3 * j + c]; },
      [&](std::size_t j) { return p.weight[j]; }, sigma, prior);
}

TEST(EliminatedAlbedo, MatchesDirectLeastSquaresWithFixedSpecular) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Problem p = MakeProblem(40, Vec3d(0.6, 0.4, 0.3), Vec3d(0.3, 0.3, 0.2), 1.0, 0.01, seed);
    const Eigen::VectorXd direct = DirectLeastSquares(p, false, 0);
    const std::array<double, 3> kd = Eliminate(p, nullptr, 1);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(kd[c], direct[c], 1e-12) << seed;
  }
}

TEST(EliminatedAlbedo, SpecularScaleMatchesDirectLeastSquaresWithItsPrior) {
  int checked = 0;
  for (const double prior : {1e-3, 1.0, 10.0}) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
      const Problem p =
          MakeProblem(40, Vec3d(0.6, 0.4, 0.3), Vec3d(0.3, 0.3, 0.2), 2.5, 0.01, seed);
      const Eigen::VectorXd direct = DirectLeastSquares(p, true, prior);
      if ((direct.array() < 0).any()) continue;  // the clamps would differ; not this test's case
      double sigma = 0;
      const std::array<double, 3> kd = Eliminate(p, &sigma, prior);
      EXPECT_NEAR(sigma, direct[3], 1e-10 * (1 + direct[3])) << prior << " " << seed;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(kd[c], direct[c], 1e-10) << prior << " " << seed;
      ++checked;
    }
  }
  EXPECT_GT(checked, 40);
}

TEST(EliminatedAlbedo, NoHighlightLeavesTheScaleAtOne) {
  Problem p = MakeProblem(40, Vec3d(0.6, 0.4, 0.3), Vec3d(0.3, 0.3, 0.2), 1.0, 0.0, 3);
  for (auto& f : p.factors) f.specular = 0;
  double sigma = 0;
  const std::array<double, 3> kd = Eliminate(p, &sigma, 1);
  EXPECT_DOUBLE_EQ(sigma, 1.0);
  EXPECT_GT(kd[0], 0.0);
}

}  // namespace
}  // namespace iphong::solve
