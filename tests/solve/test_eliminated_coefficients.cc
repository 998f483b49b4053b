// The closed-form elimination of kd and ks against direct least squares over the same unknowns
// (QR), with the non-negativity found by trying every subset of free coefficients; and the
// censored cost of shadows.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <random>

#include "solve/internal.h"

namespace iphong::solve {
namespace {

struct Problem {
  std::vector<reflectance::LightFactors<double>> factors;
  std::vector<double> weight, y;  // y: K × 3
};

Problem MakeProblem(int k, const Vec3d& kd, const Vec3d& ks, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n(0, noise);
  Problem p;
  for (int j = 0; j < k; ++j) {
    const double d = u(rng) < 0.2 ? 0.0 : u(rng);  // some lights in attached shadow
    const double s = d > 0 ? std::pow(u(rng), 8) : 0.0;
    p.factors.push_back({d, s});
    p.weight.push_back(u(rng) < 0.1 ? 0.0 : 0.2 + u(rng));
    for (int c = 0; c < 3; ++c) p.y.push_back(kd[c] * d + ks[c] * s + n(rng));
  }
  return p;
}

// min Σ_j w_j (y_jc − kd d_j − ks s_j)² + λ ks² over kd, ks ≥ 0 for channel c (λ the ridge,
// internal::kKsRidge: one more row √λ·ks = 0): the best of the feasible least-squares solutions
// on every subset of the two coefficients.
std::pair<double, double> DirectNonNegative(const Problem& p, int c) {
  const int k = static_cast<int>(p.factors.size());
  double best_cost = INFINITY;
  std::pair<double, double> best{0, 0};
  for (int subset = 0; subset < 4; ++subset) {
    const bool use_d = subset & 1, use_s = subset & 2;
    const int unknowns = use_d + use_s;
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(k + 1, std::max(unknowns, 1));
    Eigen::VectorXd b = Eigen::VectorXd::Zero(k + 1);
    if (use_s) a(k, use_d ? 1 : 0) = std::sqrt(internal::kKsRidge);
    for (int j = 0; j < k; ++j) {
      const double r = std::sqrt(p.weight[j]);
      int col = 0;
      if (use_d) a(j, col++) = r * p.factors[j].diffuse;
      if (use_s) a(j, col++) = r * p.factors[j].specular;
      b(j) = r * p.y[3 * j + c];
    }
    Eigen::VectorXd x = Eigen::VectorXd::Zero(std::max(unknowns, 1));
    if (unknowns > 0) x = a.colPivHouseholderQr().solve(b);
    if (unknowns > 0 && (x.array() < 0).any()) continue;
    const double cost = unknowns > 0 ? (a * x - b).squaredNorm() : b.squaredNorm();
    if (cost < best_cost) {
      best_cost = cost;
      best = {use_d ? x[0] : 0.0, use_s ? x[use_d ? 1 : 0] : 0.0};
    }
  }
  return best;
}

std::array<internal::CoefficientPair<double>, 3> Eliminate(const Problem& p, const double* ks) {
  return internal::EliminatedCoefficients<double>(
      p.factors, 3, ks, [&](std::size_t j, int c) { return p.y[3 * j + c]; },
      [&](std::size_t j) { return p.weight[j]; });
}

TEST(EliminatedCoefficients, FreeKsMatchesDirectNonNegativeLeastSquares) {
  int boundary = 0;
  for (unsigned seed = 1; seed <= 40; ++seed) {
    // Channel 2 has no specular term and noise: its free ks often leaves the quadrant.
    const Problem p = MakeProblem(40, Vec3d(0.6, 0.4, 0.3), Vec3d(0.5, 0.2, 0.0), 0.02, seed);
    const auto got = Eliminate(p, nullptr);
    for (int c = 0; c < 3; ++c) {
      const auto [kd, ks] = DirectNonNegative(p, c);
      EXPECT_NEAR(got[c].kd, kd, 1e-10) << seed << " " << c;
      EXPECT_NEAR(got[c].ks, ks, 1e-10) << seed << " " << c;
      boundary += ks == 0;
    }
  }
  EXPECT_GT(boundary, 5);  // the clamped branch was exercised
}

TEST(EliminatedCoefficients, RecoversExactCoefficientsOfAnyColour) {
  // Metallic: the highlight takes the surface's colour; plastic: white. Both found as they are.
  for (const Vec3d& ks : {Vec3d(0.5, 0.3, 0.1), Vec3d(0.4, 0.4, 0.4)}) {
    const Problem p = MakeProblem(30, Vec3d(0.6, 0.35, 0.12), ks, 0.0, 7);
    const auto got = Eliminate(p, nullptr);
    for (int c = 0; c < 3; ++c) {
      // Exact up to the ridge's pull toward 0, a fraction λ/(Σ w s² + λ) of ks here (the lobe
      // seen at about its peak by a few lights): below 0.3 %.
      EXPECT_NEAR(got[c].ks, ks[c], 3e-3 * ks[c]);
      EXPECT_NEAR(got[c].kd, Vec3d(0.6, 0.35, 0.12)[c], 3e-3 * ks[c]);
      EXPECT_NEAR(got[c].ks, DirectNonNegative(p, c).second, 1e-10);
    }
  }
}

TEST(EliminatedCoefficients, KnownKsSolvesKdAlone) {
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const Vec3d ks(0.3, 0.3, 0.2);
    const Problem p = MakeProblem(40, Vec3d(0.6, 0.4, 0.3), ks, 0.01, seed);
    const auto got = Eliminate(p, ks.data());
    for (int c = 0; c < 3; ++c) {
      double num = 0, den = 0;
      for (std::size_t j = 0; j < p.factors.size(); ++j) {
        num +=
            p.weight[j] * p.factors[j].diffuse * (p.y[3 * j + c] - ks[c] * p.factors[j].specular);
        den += p.weight[j] * p.factors[j].diffuse * p.factors[j].diffuse;
      }
      EXPECT_NEAR(got[c].kd, num / den, 1e-12);
      EXPECT_EQ(got[c].ks, ks[c]);
    }
  }
}

TEST(EliminatedCoefficients, NoHighlightMeansNoKs) {
  Problem p = MakeProblem(40, Vec3d(0.6, 0.4, 0.3), Vec3d::Zero(), 0.0, 3);
  for (auto& f : p.factors) f.specular = 0;
  const auto got = Eliminate(p, nullptr);
  EXPECT_EQ(got[0].ks, 0.0);
  EXPECT_NEAR(got[0].kd, 0.6, 1e-12);
}

TEST(CensoredCost, ChargesDarknessAtMostTheThreshold) {
  const double t = 0.1;
  EXPECT_DOUBLE_EQ(internal::CensoredCost(0.05, t), 0.0025);   // brighter: squared
  EXPECT_DOUBLE_EQ(internal::CensoredCost(-0.05, t), 0.0025);  // a little darker: squared
  EXPECT_DOUBLE_EQ(internal::CensoredCost(-0.5, t), 0.01);     // shadowed: t²
  EXPECT_DOUBLE_EQ(internal::CensoredCost(0.5, t), 0.25);      // never censored above
  EXPECT_EQ(internal::CensoredWeight(-0.5, t), 0.0);
  EXPECT_EQ(internal::CensoredWeight(-0.05, t), 1.0);
}

TEST(BrightnessScale, IsTheMeanOfTheBrightestTenth) {
  std::vector<double> v;
  for (int i = 1; i <= 40; ++i) v.push_back(i);
  EXPECT_DOUBLE_EQ(internal::BrightnessScale(v), (40 + 39 + 38 + 37) / 4.0);
  std::vector<double> few = {0.2, 0.5, 0.1};
  EXPECT_DOUBLE_EQ(internal::BrightnessScale(few), 0.5);
}

}  // namespace
}  // namespace iphong::solve
