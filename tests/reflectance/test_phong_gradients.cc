// ceres::Jet derivatives of the templated model against central finite differences, at random
// configurations and at the boundaries a solver can reach (N·L = 0, R·V = 0, shininess → 0).
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

#include "reflectance/lighting.h"
#include "reflectance/phong.h"

namespace iphong::reflectance {
namespace {

// Parameters: normal (3), view (3), light (3), kd (3), ks (3), shininess (1).
constexpr int kParams = 16;
using Params = std::array<double, kParams>;
using Jet = ceres::Jet<double, kParams>;

template <typename T>
Vec3T<T> Term(const std::array<T, kParams>& p, const ModelOptions& options) {
  const Vec3T<T> normal(p[0], p[1], p[2]), view(p[3], p[4], p[5]), light(p[6], p[7], p[8]);
  MaterialT<T> m;
  m.kd = Vec3T<T>(p[9], p[10], p[11]);
  m.ks = Vec3T<T>(p[12], p[13], p[14]);
  m.shininess = p[15];
  const Vec3T<T> intensity(T(1.0), T(0.8), T(0.6));
  return LightTerm(normal, view, light, intensity, intensity, m, options);
}

// Jacobian (3 × 16) by autodiff.
Eigen::Matrix<double, 3, kParams> JetJacobian(const Params& p, const ModelOptions& o,
                                              Vec3d* value) {
  std::array<Jet, kParams> x;
  for (int i = 0; i < kParams; ++i) x[i] = Jet(p[i], i);
  const Vec3T<Jet> y = Term(x, o);
  Eigen::Matrix<double, 3, kParams> jacobian;
  for (int c = 0; c < 3; ++c) {
    (*value)[c] = y[c].a;
    jacobian.row(c) = y[c].v.transpose();
  }
  return jacobian;
}

Eigen::Matrix<double, 3, kParams> NumericJacobian(const Params& p, const ModelOptions& o) {
  Eigen::Matrix<double, 3, kParams> jacobian;
  for (int i = 0; i < kParams; ++i) {
    const double h = 1e-6 * std::max(1.0, std::abs(p[i]));
    Params plus = p, minus = p;
    plus[i] += h;
    minus[i] -= h;
    jacobian.col(i) = (Term(plus, o) - Term(minus, o)) / (2 * h);
  }
  return jacobian;
}

Params RandomParams(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1), pos(0.05, 1);
  auto unit_upper = [&] {
    Vec3d v;
    do {
      v = Vec3d(u(rng), u(rng), pos(rng));
    } while (v.norm() < 0.2);
    return v.normalized();
  };
  Params p;
  const Vec3d n = unit_upper(), v = unit_upper(), l = unit_upper();
  for (int c = 0; c < 3; ++c) {
    p[c] = n[c];
    p[3 + c] = v[c];
    p[6 + c] = l[c];
    p[9 + c] = pos(rng);
    p[12 + c] = pos(rng);
  }
  p[15] = 1 + 60 * pos(rng);
  return p;
}

void ExpectJacobiansAgree(const Params& p, const ModelOptions& o, double tolerance) {
  Vec3d value;
  const auto jet = JetJacobian(p, o, &value);
  const auto numeric = NumericJacobian(p, o);
  EXPECT_TRUE(value.isApprox(Term(p, o), 1e-14));
  const double scale = std::max(1.0, numeric.cwiseAbs().maxCoeff());
  EXPECT_LE((jet - numeric).cwiseAbs().maxCoeff(), tolerance * scale) << "jet:\n"
                                                                      << jet << "\nnumeric:\n"
                                                                      << numeric;
}

ModelOptions Options(Lobe lobe, PowerMode power) {
  ModelOptions o;
  o.lobe = lobe;
  o.power = power;
  return o;
}

struct LobeCase {
  Lobe lobe;
  PowerMode power;
  const char* name;
};
void PrintTo(const LobeCase& c, std::ostream* os) { *os << c.name; }

class GradientTest : public ::testing::TestWithParam<LobeCase> {};

TEST_P(GradientTest, RandomConfigurationsMatchFiniteDifferences) {
  const ModelOptions o = Options(GetParam().lobe, GetParam().power);
  std::mt19937 rng(42);
  int checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Params p = RandomParams(rng);
    // Stay away from the kinks (N·L = 0, lobe cosine = 0), where one-sided derivatives differ.
    const Vec3d n(p[0], p[1], p[2]), v(p[3], p[4], p[5]), l(p[6], p[7], p[8]);
    const Vec3d r = 2 * n.dot(l) * n - l;
    if (n.dot(l) < 1e-3 || std::abs(r.dot(v)) < 1e-3 ||
        std::abs(n.dot((l + v).normalized())) < 1e-3) {
      continue;
    }
    ExpectJacobiansAgree(p, o, 1e-5);
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST_P(GradientTest, IntegerShininessTakesFastPathWithSameDerivatives) {
  const ModelOptions o = Options(GetParam().lobe, GetParam().power);
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    Params p = RandomParams(rng);
    const Vec3d n(p[0], p[1], p[2]), l(p[6], p[7], p[8]);
    if (n.dot(l) < 1e-3) continue;
    p[15] = 10;  // integer; the Jet on shininess still has a derivative, so pow runs for it
    Vec3d value;
    const auto with_shininess_derivative = JetJacobian(p, o, &value);
    // With a constant exponent (zero derivative part) repeated squaring runs instead.
    std::array<Jet, kParams> x;
    for (int i = 0; i < kParams; ++i) x[i] = Jet(p[i], i);
    x[15] = Jet(10.0);
    const Vec3T<Jet> y = Term(x, o);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(y[c].a, value[c], 1e-13);
      for (int i = 0; i < 15; ++i) {
        EXPECT_NEAR(y[c].v[i], with_shininess_derivative(c, i),
                    1e-11 * std::max(1.0, std::abs(y[c].v[i])));
      }
      EXPECT_EQ(y[c].v[15], 0.0);
    }
  }
}

TEST_P(GradientTest, DerivativesFiniteOnBoundaries) {
  const ModelOptions o = Options(GetParam().lobe, GetParam().power);
  const double kd = 0.7, ks = 0.5;
  auto make = [&](const Vec3d& n, const Vec3d& v, const Vec3d& l, double shininess) {
    Params p;
    for (int c = 0; c < 3; ++c) {
      p[c] = n[c];
      p[3 + c] = v[c];
      p[6 + c] = l[c];
      p[9 + c] = kd;
      p[12 + c] = ks;
    }
    p[15] = shininess;
    return p;
  };
  const Vec3d z(0, 0, 1);
  const std::vector<Params> boundaries = {
      make(z, z, Vec3d(1, 0, 0), 10),                            // N·L = 0 exactly
      make(z, Vec3d(1, 0, 0), Vec3d(1, 0, 1).normalized(), 10),  // R·V = 0 exactly
      make(z, Vec3d(0.6, 0, 0.8), Vec3d(-0.6, 0, 0.8), 1e-9),    // shininess → 0
      make(z, Vec3d(0.6, 0, 0.8), Vec3d(-0.6, 0, 0.8), 0.0),     // shininess = 0
      make(z, Vec3d(-0.6, 0, 0.8), Vec3d(0.6, 0, 0.8), 1e-9),    // on the highlight, n → 0
      make(z, Vec3d(1, 0, 1e-12).normalized(), Vec3d(-1, 0, 1e-12).normalized(), 0.5),  // L ≈ −V
  };
  for (const Params& p : boundaries) {
    Vec3d value;
    const auto jacobian = JetJacobian(p, o, &value);
    EXPECT_TRUE(value.allFinite());
    EXPECT_TRUE(jacobian.allFinite()) << jacobian;
  }
}

TEST_P(GradientTest, JustInsideTheTerminatorMatchesFiniteDifferences) {
  // N·L = 1e-3: on the lit side of the kink, derivatives must match the one-sided function.
  const ModelOptions o = Options(GetParam().lobe, GetParam().power);
  Params p;
  const Vec3d n(0, 0, 1), v = Vec3d(0.3, 0.1, 0.9).normalized();
  const Vec3d l = Vec3d(-1, 0, 1e-3).normalized();
  for (int c = 0; c < 3; ++c) {
    p[c] = n[c];
    p[3 + c] = v[c];
    p[6 + c] = l[c];
    p[9 + c] = 0.5;
    p[12 + c] = 0.4;
  }
  p[15] = 3.5;
  ExpectJacobiansAgree(p, o, 1e-4);
}

// Constant view and light as plain numbers with a Jet normal (what the solvers pass) give the
// values and derivatives of the all-Jet evaluation.
TEST_P(GradientTest, PlainDirectionsWithJetNormalAgree) {
  const ModelOptions o = Options(GetParam().lobe, GetParam().power);
  using Jet2 = ceres::Jet<double, 2>;
  std::mt19937 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    const Params p = RandomParams(rng);
    const Vec3T<Jet2> normal(Jet2(p[0], 0), Jet2(p[1], 1), Jet2(p[2]));
    const Vec3d view(p[3], p[4], p[5]), light(p[6], p[7], p[8]);
    const Jet2 shininess(p[15]);
    const LightFactors<Jet2> mixed =
        ShadingFactors<Jet2, double>(normal, view, light, shininess, o);
    const LightFactors<Jet2> jets =
        ShadingFactors<Jet2>(normal, view.cast<Jet2>(), light.cast<Jet2>(), shininess, o);
    // Equal up to rounding (H is normalized in double instead of in Jets).
    EXPECT_DOUBLE_EQ(mixed.diffuse.a, jets.diffuse.a);
    EXPECT_NEAR(mixed.specular.a, jets.specular.a, 1e-13 * (1 + jets.specular.a));
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(mixed.diffuse.v[i], jets.diffuse.v[i], 1e-12);
      EXPECT_NEAR(mixed.specular.v[i], jets.specular.v[i],
                  1e-12 * (1 + std::abs(jets.specular.v[i])));
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Lobes, GradientTest,
    ::testing::Values(LobeCase{Lobe::kPhong, PowerMode::kExact, "PhongExact"},
                      LobeCase{Lobe::kBlinnPhong, PowerMode::kExact, "BlinnPhongExact"},
                      LobeCase{Lobe::kPhong, PowerMode::kFastApprox, "PhongFastApprox"},
                      LobeCase{Lobe::kBlinnPhong, PowerMode::kFastApprox, "BlinnPhongFastApprox"},
                      LobeCase{Lobe::kLambert, PowerMode::kExact, "Lambert"},
                      LobeCase{Lobe::kNormalCentred, PowerMode::kExact, "NormalCentredExact"},
                      LobeCase{Lobe::kNormalCentred, PowerMode::kFastApprox,
                               "NormalCentredFastApprox"},
                      // The shininess' place holds the facets' slope; its kinks (L·V =
                      // (N·L)(N·V), N·L = N·V) are met within the differences' step by chance
                      // only.
                      LobeCase{Lobe::kOrenNayar, PowerMode::kExact, "OrenNayar"}),
    [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace iphong::reflectance

namespace iphong::reflectance {
namespace {

// A point light's irradiance E(X) = Φ·(a·(X − S)/|X − S|)^μ/|X − S|² (LightAt) as the surface
// point X moves: its Jet derivative against central differences, for an isotropic light, a
// Lambertian LED (μ = 1) and a narrow one (μ = 4.3, through exp/log).
TEST(LedGradient, IrradianceAlongTheSurfaceMatchesFiniteDifferences) {
  using Jet3 = ceres::Jet<double, 3>;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (double mu : {0.0, 1.0, 4.3}) {
    const Light light =
        Light::Led(Vec3d(30, 40, 0), Vec3d(2e4, 1e4, 5e3), Vec3d(-0.3, -0.4, -1), mu);
    for (int trial = 0; trial < 20; ++trial) {
      const Vec3d x(10 * u(rng), 10 * u(rng), -200 + 10 * u(rng));
      Vec3T<Jet3> xj(Jet3(x[0], 0), Jet3(x[1], 1), Jet3(x[2], 2)), dir, diffuse, specular;
      ASSERT_TRUE(LightAt<Jet3>(light, xj, &dir, &diffuse, &specular));
      for (int k = 0; k < 3; ++k) {
        const double h = 1e-4;
        Vec3d xp = x, xm = x, d, ep, em, s;
        xp[k] += h;
        xm[k] -= h;
        LightAt<double>(light, xp, &d, &ep, &s);
        LightAt<double>(light, xm, &d, &em, &s);
        for (int c = 0; c < 3; ++c) {
          const double fd = (ep[c] - em[c]) / (2 * h);
          EXPECT_NEAR(diffuse[c].v[k], fd, 1e-6 * std::abs(diffuse[c].a) + 1e-12)
              << "mu " << mu << " coordinate " << k;
        }
      }
    }
  }
}

}  // namespace
}  // namespace iphong::reflectance
