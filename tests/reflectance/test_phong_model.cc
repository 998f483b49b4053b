// The templated model against the seeds: seed 002's worked example, seed 003's rules, closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "reflectance/lighting.h"
#include "reflectance/material.h"
#include "reflectance/phong.h"

namespace iphong::reflectance {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3d ToVec3(const nlohmann::json& j) { return Vec3d(j[0], j[1], j[2]); }

Vec3d InPlaneXZ(double angle_from_z_rad) {
  return Vec3d(std::sin(angle_from_z_rad), 0, std::cos(angle_from_z_rad));
}

Material Shiny(double shininess) {
  Material m;
  m.ka = Vec3d::Zero();
  m.kd = Vec3d(0.5, 0.4, 0.3);
  m.ks = Vec3d(0.8, 0.8, 0.8);
  m.shininess = shininess;
  return m;
}

TEST(PhongModel, Seed002WorkedExample) {
  std::ifstream file(IPHONG_FIXTURES_DIR "/seed002_example.json");
  ASSERT_TRUE(file) << "missing fixture seed002_example.json";
  const auto fixture = nlohmann::json::parse(file);
  Material material;
  material.ka = ToVec3(fixture["material"]["ka"]);
  material.kd = ToVec3(fixture["material"]["kd"]);
  material.ks = ToVec3(fixture["material"]["ks"]);
  material.shininess = fixture["material"]["shininess"];
  Lighting lighting;
  lighting.ambient = ToVec3(fixture["ambient"]);
  for (const auto& l : fixture["lights"]) {
    lighting.lights.push_back(Light::Directional(ToVec3(l["direction"]), ToVec3(l["intensity"])));
  }
  const Vec3d view_cam = -ToVec3(fixture["view_seed"]).normalized();
  const Vec3d color = Shade(ToVec3(fixture["normal"]), view_cam, Vec3d::Zero().eval(), material,
                            lighting, ModelOptions{});
  const Vec3d expected = ToVec3(fixture["expected_intensity"]);
  const double tolerance = fixture["tolerance"];
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(color[c], expected[c], tolerance) << "channel " << c;
}

TEST(PhongModel, Seed002SecondLightBehindSurfaceAddsNothing) {
  const Material m = Shiny(10);
  const Vec3d n(0, 0, 1), v = Vec3d(-0.2357, -0.2357, 0.94281).normalized();
  const Vec3d behind =
      LightTerm<double>(n, v, Vec3d(0, 0, -1), Vec3d::Ones(), Vec3d::Ones(), m, ModelOptions{});
  EXPECT_EQ(behind, Vec3d::Zero());
}

TEST(PhongModel, GrazingLightContributesNothing) {
  // N·L = 0 exactly: neither diffuse nor specular (seed 003: only positive dot products count).
  const Vec3d n(0, 0, 1);
  const Vec3d l(1, 0, 0);
  for (Lobe lobe : {Lobe::kPhong, Lobe::kBlinnPhong, Lobe::kLambert}) {
    ModelOptions o;
    o.lobe = lobe;
    EXPECT_EQ(LightTerm<double>(n, Vec3d(-1, 0, 0), l, Vec3d::Ones(), Vec3d::Ones(), Shiny(1), o),
              Vec3d::Zero());
  }
}

TEST(PhongModel, NoSpecularWhereLightIsBehindEvenIfMirrorDirectionSeesViewer) {
  // N·L < 0 but R·V = 1: without seed 003's second rule the specular term would be ks.
  const Vec3d n(0, 0, 1);
  const Vec3d l = Vec3d(0, 0.6, -0.8);
  const Vec3d r = 2 * n.dot(l) * n - l;
  ASSERT_NEAR(r.dot(r.normalized()), 1.0, 1e-12);
  EXPECT_EQ(SpecularLobe<double>(n, r, l, 10.0, ModelOptions{}), 0.0);
  EXPECT_EQ(LightTerm<double>(n, r, l, Vec3d::Ones(), Vec3d::Ones(), Shiny(10), ModelOptions{}),
            Vec3d::Zero());
}

TEST(PhongModel, SpecularDropsWhenMirrorDirectionFacesAwayFromViewer) {
  // Light 60° to one side, viewer 60° to the same side: R·V = cos(120°) < 0, only diffuse.
  const Vec3d n(0, 0, 1), l = InPlaneXZ(kPi / 3), v = InPlaneXZ(kPi / 3);
  const Material m = Shiny(5);
  const Vec3d term = LightTerm<double>(n, v, l, Vec3d::Ones(), Vec3d::Ones(), m, ModelOptions{});
  EXPECT_TRUE(term.isApprox(m.kd * 0.5, 1e-12)) << term.transpose();
}

TEST(PhongModel, ClosedFormLobeInPlane) {
  // N = z, light at θ, viewer at −φ (other side): R is at −θ, so R·V = cos(θ − φ).
  const Vec3d n(0, 0, 1);
  for (double theta : {0.1, 0.4, 0.9}) {
    for (double phi : {0.0, 0.3, 0.7}) {
      for (double shininess : {1.0, 7.0, 12.8, 100.0}) {
        const double lobe =
            SpecularLobe<double>(n, InPlaneXZ(-phi), InPlaneXZ(theta), shininess, ModelOptions{});
        EXPECT_NEAR(lobe, std::pow(std::cos(theta - phi), shininess), 1e-12);
      }
    }
  }
}

TEST(PhongModel, NormalCentredLobeIsTheCosinePowerWhateverTheView) {
  // (N·L)^n: the light at θ from N gives cos^n θ from every viewer, and Phong's value only where
  // the viewer looks along N (R·V = N·L there); nothing from behind.
  ModelOptions foil;
  foil.lobe = Lobe::kNormalCentred;
  const Vec3d n(0, 0, 1);
  for (double theta : {0.0, 0.4, 1.2}) {
    for (double phi : {0.0, 0.3, 0.7}) {
      for (double shininess : {1.0, 4.8, 12.8}) {
        EXPECT_NEAR(SpecularLobe<double>(n, InPlaneXZ(phi), InPlaneXZ(theta), shininess, foil),
                    std::pow(std::cos(theta), shininess), 1e-12);
      }
    }
    EXPECT_NEAR(SpecularLobe<double>(n, n, InPlaneXZ(theta), 7.0, foil),
                SpecularLobe<double>(n, n, InPlaneXZ(theta), 7.0, ModelOptions{}), 1e-12);
  }
  EXPECT_EQ(SpecularLobe<double>(n, n, InPlaneXZ(1.7), 3.0, foil), 0.0);
}

TEST(PhongModel, OrenNayarIsThePapersFormulaInVectors) {
  // Oren and Nayar's qualitative model as their paper writes it, in angles: cos θi·(A + B·
  // max(0, cos(φi − φr))·sin α·tan β), against the vector form without trigonometry.
  ModelOptions rough;
  rough.lobe = Lobe::kOrenNayar;
  const auto at = [](double theta, double phi) {
    return Vec3d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
  };
  const Vec3d n(0, 0, 1);
  int compared = 0;
  for (double slope : {0.0, 0.1, 0.3, 0.6, 1.2}) {
    const double s2 = slope * slope;
    const double a = 1 - 0.5 * s2 / (s2 + 0.33), b = 0.45 * s2 / (s2 + 0.09);
    for (double theta_i : {0.05, 0.4, 0.9, 1.4}) {
      for (double theta_r : {0.0, 0.3, 0.8, 1.3}) {
        for (double phi : {0.0, 1.0, 2.0, 3.0}) {
          const Vec3d l = at(theta_i, 0.7), v = at(theta_r, 0.7 + phi);
          const double alpha = std::max(theta_i, theta_r), beta = std::min(theta_i, theta_r);
          const double paper = std::cos(theta_i) * (a + b * std::max(0.0, std::cos(phi)) *
                                                            std::sin(alpha) * std::tan(beta));
          EXPECT_NEAR(OrenNayarDiffuse<double>(n, v, l, slope), paper, 1e-12)
              << slope << " " << theta_i << " " << theta_r << " " << phi;
          const LightFactors<double> f = ShadingFactors<double>(n, v, l, slope, rough);
          EXPECT_NEAR(f.diffuse, paper, 1e-12);
          EXPECT_EQ(f.specular, 0.0);
          ++compared;
        }
      }
    }
  }
  EXPECT_EQ(compared, 320);
  // Smooth facets are Lambert's cosine; nothing from behind the surface or toward a viewer
  // behind it; a rough surface is brighter than A·cos θi toward the viewer (its retro-reflection).
  EXPECT_NEAR(OrenNayarDiffuse<double>(n, at(1.0, 2.0), at(0.6, 0.1), 0.0), std::cos(0.6), 1e-15);
  EXPECT_EQ(OrenNayarDiffuse<double>(n, at(0.3, 0), at(1.7, 0), 0.5), 0.0);
  EXPECT_EQ(OrenNayarDiffuse<double>(n, at(1.7, 0), at(0.3, 0), 0.5), 0.0);
  EXPECT_GT(OrenNayarDiffuse<double>(n, at(1.0, 0), at(1.0, 0), 0.5), std::cos(1.0));
}

TEST(PhongModel, FullTermClosedForm) {
  const Vec3d n(0, 0, 1), l = InPlaneXZ(0.5), v = InPlaneXZ(-0.2);
  const Material m = Shiny(20);
  const Vec3d id(1.0, 0.5, 0.25), is(0.2, 0.4, 0.6);
  const Vec3d expected =
      id.cwiseProduct(m.kd) * std::cos(0.5) + is.cwiseProduct(m.ks) * std::pow(std::cos(0.3), 20);
  EXPECT_TRUE(LightTerm<double>(n, v, l, id, is, m, ModelOptions{}).isApprox(expected, 1e-12));
}

TEST(PhongModel, SeparateDiffuseAndSpecularIntensities) {
  const Vec3d n(0, 0, 1), l = InPlaneXZ(0.3), v = InPlaneXZ(-0.3);  // on the highlight
  const Material m = Shiny(30);
  const Vec3d only_diffuse =
      LightTerm<double>(n, v, l, Vec3d::Ones(), Vec3d::Zero(), m, ModelOptions{});
  const Vec3d only_specular =
      LightTerm<double>(n, v, l, Vec3d::Zero(), Vec3d::Ones(), m, ModelOptions{});
  EXPECT_TRUE(only_diffuse.isApprox(m.kd * std::cos(0.3), 1e-12));
  EXPECT_TRUE(only_specular.isApprox(m.ks, 1e-12));  // R = V exactly: lobe 1
}

TEST(PhongModel, PhongAndBlinnPhongAgreeWhenViewLightAndNormalCoincide) {
  const Vec3d n = Vec3d(0.2, -0.3, 0.9).normalized();
  ModelOptions blinn;
  blinn.lobe = Lobe::kBlinnPhong;
  for (double shininess : {0.5, 1.0, 10.0, 76.8}) {
    EXPECT_NEAR(SpecularLobe<double>(n, n, n, shininess, ModelOptions{}), 1.0, 1e-12);
    EXPECT_NEAR(SpecularLobe<double>(n, n, n, shininess, blinn), 1.0, 1e-12);
  }
}

TEST(PhongModel, RetroReflectionRelatesPhongAndBlinnCosines) {
  // With V = L, H = L, so N·H = N·L = cos θ and R·V = cos 2θ = 2(N·H)² − 1.
  ModelOptions blinn;
  blinn.lobe = Lobe::kBlinnPhong;
  const Vec3d n(0, 0, 1);
  for (double theta : {0.05, 0.2, 0.5, 0.7}) {
    const Vec3d l = InPlaneXZ(theta);
    const double phong = SpecularLobe<double>(n, l, l, 1.0, ModelOptions{});
    const double blinn_cos = SpecularLobe<double>(n, l, l, 1.0, blinn);
    EXPECT_NEAR(phong, 2 * blinn_cos * blinn_cos - 1, 1e-12);
  }
}

TEST(PhongModel, LobeIntegralOverHemisphereIsTwoPiOverNPlusOne) {
  // With N = L = z the Phong lobe is (V·z)^n; ∫ over the hemisphere of views = 2π/(n + 1), so the
  // lobe's solid angle shrinks like 1/n as the shininess grows.
  const Vec3d z(0, 0, 1);
  const int steps = 20000;
  for (double n : {1.0, 10.0, 100.0, 1000.0}) {
    double integral = 0;
    for (int i = 0; i < steps; ++i) {  // midpoint rule in θ; the φ integral is 2π by symmetry
      const double theta = (i + 0.5) * (kPi / 2) / steps;
      const Vec3d v(std::sin(theta), 0, std::cos(theta));
      integral += SpecularLobe<double>(z, v, z, n, ModelOptions{}) * std::sin(theta);
    }
    integral *= 2 * kPi * (kPi / 2) / steps;
    EXPECT_NEAR(integral, 2 * kPi / (n + 1), 1e-3 * 2 * kPi / (n + 1)) << "n = " << n;
  }
}

TEST(PhongModel, LargerShininessConcentratesTheLobe) {
  const Vec3d z(0, 0, 1);
  const Vec3d off_peak = InPlaneXZ(0.2);  // 11.5° from the mirror direction
  double previous = 1.0;
  for (double n : {1.0, 10.0, 100.0, 1000.0}) {
    EXPECT_NEAR(SpecularLobe<double>(z, z, z, n, ModelOptions{}), 1.0, 1e-12);  // peak stays 1
    const double value = SpecularLobe<double>(z, off_peak, z, n, ModelOptions{});
    EXPECT_LT(value, previous);
    previous = value;
  }
  EXPECT_LT(previous, 1e-8);
}

TEST(PhongModel, IntegerFastPathEqualsPow) {
  for (int n = 0; n <= 300; n += 7) {
    for (double c : {1e-9, 0.01, 0.3, 0.77, 0.999, 1.0}) {
      int exponent = -1;
      ASSERT_TRUE(detail::IsConstantInteger(static_cast<double>(n), &exponent));
      ASSERT_EQ(exponent, n);
      EXPECT_NEAR(LobePower(c, 1 - c, static_cast<double>(n), ModelOptions{}), std::pow(c, n),
                  1e-13 * std::max(1.0, std::pow(c, n)));
    }
  }
  int ignored = 0;
  EXPECT_FALSE(detail::IsConstantInteger(12.8, &ignored));
  EXPECT_FALSE(detail::IsConstantInteger(-2.0, &ignored));
}

TEST(PhongModel, FastApproximationFollowsSeed003) {
  ModelOptions fast;
  fast.power = PowerMode::kFastApprox;
  fast.fast_approx_log2_gamma = 2;  // γ = 4
  const Vec3d z(0, 0, 1);
  // λ = |R − V|²/2 equals 1 − R·V for unit vectors; the value is (1 − (n/4)λ)^4.
  for (double angle : {0.0, 0.1, 0.3, 0.6}) {
    const Vec3d v = InPlaneXZ(angle);
    const double lambda = 1 - std::cos(angle);
    const double base = std::max(0.0, 1 - (16.0 / 4) * lambda);
    EXPECT_NEAR(SpecularLobe<double>(z, v, z, 16.0, fast), std::pow(base, 4), 1e-12);
  }
  // It approaches the exact lobe as γ grows (βλ small): (1 − βλ)^γ → e^{−nλ} ≈ (1 − λ)^n.
  const Vec3d v = InPlaneXZ(0.15);
  const double exact = SpecularLobe<double>(z, v, z, 32.0, ModelOptions{});
  double previous_error = 1;
  for (int k : {1, 2, 4, 8}) {
    fast.fast_approx_log2_gamma = k;
    const double error = std::abs(SpecularLobe<double>(z, v, z, 32.0, fast) - exact);
    EXPECT_LT(error, previous_error) << "k = " << k;
    previous_error = error;
  }
  EXPECT_LT(previous_error, 0.01);
}

TEST(PhongModel, FloatAndDoubleAgree) {
  const Vec3d n = Vec3d(0.1, 0.2, 0.97).normalized(), v = Vec3d(-0.1, 0.05, 1).normalized();
  const Vec3d l = Vec3d(0.4, 0.3, 0.8).normalized();
  const Material m = Shiny(12.8);
  const Vec3d d = LightTerm<double>(n, v, l, Vec3d::Ones(), Vec3d::Ones(), m, ModelOptions{});
  const Vec3f f = LightTerm<float>(n.cast<float>(), v.cast<float>(), l.cast<float>(), Vec3f::Ones(),
                                   Vec3f::Ones(), CastMaterial<float>(m), ModelOptions{});
  EXPECT_TRUE(f.cast<double>().isApprox(d, 1e-5));
}

TEST(PhongModel, PointLightDirectionAndInverseSquareFalloff) {
  Lighting lighting;
  lighting.lights = {Light::Point(Vec3d(0, 0, 2), Vec3d::Ones(), /*falloff=*/true)};
  Material m;
  m.kd = Vec3d::Ones();
  ModelOptions lambert;
  lambert.lobe = Lobe::kLambert;
  // A point at (1, 0, 0) with normal z: L = (−1, 0, 2)/√5, d² = 5, N·L = 2/√5.
  const Vec3d color =
      Shade<double>(Vec3d(0, 0, 1), Vec3d(0, 0, 1), Vec3d(1, 0, 0), m, lighting, lambert);
  EXPECT_NEAR(color[0], (2 / std::sqrt(5.0)) / 5.0, 1e-12);
  lighting.lights[0].inverse_square_falloff = false;
  EXPECT_NEAR(
      Shade<double>(Vec3d(0, 0, 1), Vec3d(0, 0, 1), Vec3d(1, 0, 0), m, lighting, lambert)[0],
      2 / std::sqrt(5.0), 1e-12);
}

TEST(PhongModel, AmbientIsAddedOnceWhateverTheLights) {
  Lighting lighting;
  lighting.ambient = Vec3d(1, 0.5, 0.25);
  Material m = Shiny(10);
  m.ka = Vec3d(0.2, 0.2, 0.2);
  const Vec3d n(0, 0, 1);
  EXPECT_TRUE(Shade<double>(n, n, Vec3d::Zero(), m, lighting, ModelOptions{})
                  .isApprox(Vec3d(0.2, 0.1, 0.05), 1e-15));
  lighting.lights = {Light::Directional(Vec3d(0, 0, -1), Vec3d::Ones())};  // behind
  EXPECT_TRUE(Shade<double>(n, n, Vec3d::Zero(), m, lighting, ModelOptions{})
                  .isApprox(Vec3d(0.2, 0.1, 0.05), 1e-15));
}

}  // namespace
}  // namespace iphong::reflectance
