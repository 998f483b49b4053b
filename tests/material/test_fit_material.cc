// Material fitting on renders of known materials: every preset recovered, the model chosen by
// held-out prediction, standard errors that cover the truth as often as they claim, bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <ceres/ceres.h>
#include "geometry/primitives.h"

#include "material/fit.h"
#include "material/internal.h"
#include "reflectance/material.h"
#include "render/renderer.h"

namespace iphong::material {
namespace {

using reflectance::Light;
using reflectance::Lobe;

struct Capture {
  solve::PhotometricData data;
  std::vector<Vec3d> normals;  // per observed pixel
};

// A sphere under 24 hemisphere lights (elevations 30°–88°, RGB intensity (1, 0.9, 0.8)) and
// ambient Ia, rendered per light, with Gaussian noise σ added to every value.
Capture RenderSphere(const reflectance::Material& material, Lobe lobe, const Vec3d& ambient,
                     double sigma = 0, int size = 64, unsigned seed = 1) {
  render::Scene scene;
  scene.camera = geometry::Camera::Orthographic(size, size, 2.0);
  scene.lighting.ambient = ambient;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  const int lights = 24;
  for (int i = 0; i < lights; ++i) {
    const double z = 1 - 0.5 * (i + 0.5) / lights, r = std::sqrt(1 - z * z);
    scene.lighting.lights.push_back(Light::Directional(
        Vec3d(r * std::cos(golden * i), r * std::sin(golden * i), z), Vec3d(1.0, 0.9, 0.8)));
  }
  render::SceneObject sphere;
  sphere.mesh = geometry::MakeSphere(0.9, 6);
  sphere.material = material;
  scene.objects.push_back(sphere);
  render::RenderOptions options;
  options.model.lobe = lobe;
  render::RenderOutput out = render::Render(scene, options, true);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0, static_cast<float>(sigma));
  std::vector<const float*> images;
  std::vector<Vec3d> dirs, intensities;
  for (std::size_t j = 0; j < out.per_light.size(); ++j) {
    if (sigma > 0) {
      for (float& v : out.per_light[j].pixels) v += noise(rng);
    }
    images.push_back(out.per_light[j].pixels.data());
    dirs.push_back(scene.lighting.lights[j].direction_cam);
    intensities.push_back(scene.lighting.lights[j].diffuse_intensity);
  }
  Capture c;
  c.data = solve::GatherObservations(images, size, size, out.mask, dirs, intensities);
  for (int p : c.data.pixels) {
    const float* n = out.normal_cam.pixels.data() + 3 * std::size_t(p);
    c.normals.emplace_back(n[0], n[1], n[2]);
  }
  return c;
}

// |estimate − truth| within `relative` of the truth, or of `scale` where the truth is 0.
void ExpectClose(double estimate, double truth, double relative, double scale,
                 const std::string& what) {
  EXPECT_LE(std::abs(estimate - truth), relative * (truth != 0 ? std::abs(truth) : scale))
      << what << ": " << estimate << " vs " << truth;
}

Vec3d MedianAlbedo(const MaterialFit& fit) {
  Vec3d median;
  for (int c = 0; c < 3; ++c) {
    std::vector<double> v;
    for (const Vec3d& a : fit.albedo) {
      if (a.allFinite()) v.push_back(a[c]);
    }
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    median[c] = v[v.size() / 2];
  }
  return median;
}

TEST(FitMaterial, EveryPresetNoiseFreeWithinHalfAPercentAndTheRightModel) {
  const Vec3d ambient(0.3, 0.3, 0.3);
  for (const reflectance::MaterialPreset& preset : reflectance::MaterialPresets()) {
    SCOPED_TRACE(preset.name);
    const reflectance::Material& m = preset.material;
    const Capture c = RenderSphere(m, Lobe::kPhong, ambient);
    const MaterialFit fit = FitMaterial(c.data, c.normals, MaterialFitOptions{});
    const ModelFit& best = fit.best();
    const bool matte = m.ks.maxCoeff() == 0;
    EXPECT_EQ(best.lobe, matte ? Lobe::kLambert : Lobe::kPhong) << fit.choice_note;
    const double scale = std::max(m.kd.maxCoeff(), m.ks.maxCoeff());
    const Vec3d kd = MedianAlbedo(fit);
    for (int ch = 0; ch < 3; ++ch) {
      ExpectClose(best.ambient_term[ch], ambient[ch] * m.ka[ch], 0.005, scale, "ka*Ia");
      ExpectClose(kd[ch], m.kd[ch], 0.005, scale, "kd");
      if (!matte) ExpectClose(best.ks[ch], m.ks[ch], 0.005, scale, "ks");
    }
    if (!matte) ExpectClose(best.shininess, m.shininess, 0.005, 1, "shininess");
  }
}

TEST(FitMaterial, BlinnPhongDataIsRecognisedAsBlinnPhong) {
  const reflectance::Material m = reflectance::FindMaterialPreset("plastic").material;
  const Capture c = RenderSphere(m, Lobe::kBlinnPhong, Vec3d(0.2, 0.2, 0.2));
  const MaterialFit fit = FitMaterial(c.data, c.normals, MaterialFitOptions{});
  EXPECT_EQ(fit.best().lobe, Lobe::kBlinnPhong) << fit.choice_note;
  ExpectClose(fit.best().shininess, m.shininess, 0.005, 1, "shininess");
  ExpectClose(fit.best().ks[0], m.ks[0], 0.005, 1, "ks");
}

TEST(FitMaterial, UniformAlbedoIsOneParameterWithAStandardError) {
  const reflectance::Material m = reflectance::FindMaterialPreset("jade").material;
  const Capture c = RenderSphere(m, Lobe::kPhong, Vec3d(0.3, 0.3, 0.3), 0.002);
  MaterialFitOptions options;
  options.albedo = AlbedoMode::kUniform;
  options.models = {Lobe::kPhong};
  const MaterialFit fit = FitMaterial(c.data, c.normals, options);
  ASSERT_EQ(fit.best().kd.size(), 1u);
  ASSERT_EQ(fit.best().kd_se.size(), 1u);
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_NEAR(fit.best().kd[0][ch], m.kd[ch], 4 * fit.best().kd_se[0][ch]);
    EXPECT_GT(fit.best().kd_se[0][ch], 0);
    EXPECT_LT(fit.best().kd_se[0][ch], 0.01);
  }
  EXPECT_EQ(fit.best().parameters, 10u);
}

// Over 100 noisy renders, the 95 % intervals (±1.96 standard errors) of a·Ia, ks and n must
// contain the truth 90–98 % of the time: the standard errors are honest.
class Coverage : public ::testing::TestWithParam<double> {};

TEST_P(Coverage, StandardErrorsCoverTheTruth) {
  const double sigma = GetParam();
  const reflectance::Material m = reflectance::FindMaterialPreset("plastic").material;
  const Vec3d ambient(0.3, 0.3, 0.3);
  int inside = 0, total = 0, robust_inside = 0;
  for (unsigned seed = 1; seed <= 100; ++seed) {
    const Capture c = RenderSphere(m, Lobe::kPhong, ambient, sigma, 32, seed);
    MaterialFitOptions options;
    options.models = {Lobe::kPhong};
    options.threads = 1;
    const ModelFit fit = FitMaterial(c.data, c.normals, options).best();
    ASSERT_TRUE(fit.covariance_ok);
    auto count = [&](double estimate, double se, double robust_se, double truth) {
      inside += std::abs(estimate - truth) <= 1.96 * se;
      robust_inside += std::abs(estimate - truth) <= 1.96 * robust_se;
      ++total;
    };
    for (int ch = 0; ch < 3; ++ch) {
      count(fit.ambient_term[ch], fit.ambient_se[ch], fit.ambient_robust_se[ch],
            ambient[ch] * m.ka[ch]);
      count(fit.ks[ch], fit.ks_se[ch], fit.ks_robust_se[ch], m.ks[ch]);
    }
    count(fit.shininess, fit.shininess_se, fit.shininess_robust_se, m.shininess);
  }
  const double coverage = double(inside) / total;
  const double robust_coverage = double(robust_inside) / total;
  std::printf(
      "sigma %.3f: 95%% intervals contain the truth in %.1f%% of %d cases (robust %.1f%%)\n", sigma,
      100 * coverage, total, 100 * robust_coverage);
  EXPECT_GE(coverage, 0.90);
  EXPECT_LE(coverage, 0.98);
  // The sandwich estimates its meat from ~700 pixel clusters (measured: 96.0 % as well).
  EXPECT_GE(robust_coverage, 0.88);
  EXPECT_LE(robust_coverage, 0.98);
}

INSTANTIATE_TEST_SUITE_P(FitMaterial, Coverage, ::testing::Values(0.002, 0.01));

TEST(FitMaterial, ErrorsGrowSmoothlyWithNoise) {
  const reflectance::Material m = reflectance::FindMaterialPreset("plastic").material;
  double previous = 0;
  for (double sigma : {0.0, 0.002, 0.01}) {
    const Capture c = RenderSphere(m, Lobe::kPhong, Vec3d(0.3, 0.3, 0.3), sigma);
    MaterialFitOptions options;
    options.models = {Lobe::kPhong};
    const ModelFit fit = FitMaterial(c.data, c.normals, options).best();
    const double error = std::abs(fit.shininess / m.shininess - 1);
    EXPECT_GE(error + 1e-6, previous) << sigma;
    EXPECT_LT(error, 0.005 + 5 * sigma) << sigma;  // σ 0.01: within 5 %
    EXPECT_NEAR(fit.sigma, sigma, 0.1 * sigma + 1e-4) << "the noise estimate";
    previous = error;
  }
}

// The refinement's derivatives (Ceres's automatic ones through the shared model and, with kd
// eliminated, through its closed form) against central differences of the same residuals.
TEST(FitMaterial, ResidualDerivativesMatchFiniteDifferences) {
  reflectance::Material m = reflectance::FindMaterialPreset("plastic").material;
  const Capture c = RenderSphere(m, Lobe::kPhong, Vec3d(0.3, 0.3, 0.3), 0.01, 24);
  MaterialFitOptions options;
  std::vector<std::size_t> with_normal;
  std::vector<int> group_of;
  const internal::Sample s =
      internal::BuildSample(c.data, c.normals, options, &with_normal, &group_of);
  for (Lobe lobe : {Lobe::kPhong, Lobe::kBlinnPhong}) {
    for (bool eliminate : {true, false}) {
      for (std::size_t p : {s.size() / 3, s.size() / 2}) {
        std::vector<int> lights;
        for (int j = 0; j < s.lights; ++j) lights.push_back(j);
        std::unique_ptr<ceres::CostFunction> cost(
            internal::PixelCost(s, p, lights, lobe, eliminate));
        std::vector<std::vector<double>> params = {
            {0.05, 0.04, 0.03}, {0.3, 0.25, 0.2}, {std::log(17.0)}, {0.5, 0.4, 0.3}};
        if (eliminate) params.pop_back();
        const int m_res = cost->num_residuals();
        std::vector<const double*> blocks;
        for (auto& b : params) blocks.push_back(b.data());
        std::vector<std::vector<double>> jac(params.size());
        std::vector<double*> jac_ptr;
        for (std::size_t b = 0; b < params.size(); ++b) {
          jac[b].resize(m_res * params[b].size());
          jac_ptr.push_back(jac[b].data());
        }
        std::vector<double> r(m_res), plus(m_res), minus(m_res);
        ASSERT_TRUE(cost->Evaluate(blocks.data(), r.data(), jac_ptr.data()));
        double largest = 0, worst = 0;
        for (std::size_t b = 0; b < params.size(); ++b)
          for (std::size_t k = 0; k < params[b].size(); ++k) {
            const double h = 1e-6, x = params[b][k];
            params[b][k] = x + h;
            cost->Evaluate(blocks.data(), plus.data(), nullptr);
            params[b][k] = x - h;
            cost->Evaluate(blocks.data(), minus.data(), nullptr);
            params[b][k] = x;
            for (int i = 0; i < m_res; ++i) {
              const double fd = (plus[i] - minus[i]) / (2 * h);
              const double ad = jac[b][i * params[b].size() + k];
              largest = std::max(largest, std::abs(ad));
              worst = std::max(worst, std::abs(ad - fd));
            }
          }
        EXPECT_GT(largest, 0.1);
        EXPECT_LT(worst, 1e-7 * std::max(1.0, largest))
            << reflectance::LobeName(lobe) << (eliminate ? ", kd eliminated" : ", kd a block");
      }
    }
  }
}

// The standard errors come from one pass of Ceres's Jacobians (JᵀJ is 7×7); ceres::Covariance on
// the same residuals at the same optimum must give the same numbers.
TEST(FitMaterial, StandardErrorsEqualCeresCovariance) {
  const reflectance::Material m = reflectance::FindMaterialPreset("plastic").material;
  const Capture c = RenderSphere(m, Lobe::kPhong, Vec3d(0.3, 0.3, 0.3), 0.005, 32);
  MaterialFitOptions options;
  options.models = {Lobe::kPhong};
  const MaterialFit fit = FitMaterial(c.data, c.normals, options);
  const ModelFit& f = fit.best();
  ASSERT_EQ(fit.censored, 0u);  // so every usable observation is in the fit
  std::vector<std::size_t> with_normal;
  std::vector<int> group_of;
  const internal::Sample s =
      internal::BuildSample(c.data, c.normals, options, &with_normal, &group_of);
  double ambient[3] = {f.ambient_term[0], f.ambient_term[1], f.ambient_term[2]};
  double ks[3] = {f.ks[0], f.ks[1], f.ks[2]};
  double log_n[1] = {std::log(f.shininess)};
  ceres::Problem problem;
  for (std::size_t p = 0; p < s.size(); ++p) {
    std::vector<int> lights;
    for (int j = 0; j < s.lights; ++j) {
      if (s.usable[p * s.lights + j]) lights.push_back(j);
    }
    if (lights.empty()) continue;
    problem.AddResidualBlock(internal::PixelCost(s, p, lights, Lobe::kPhong, true), nullptr,
                             ambient, ks, log_n);
  }
  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::DENSE_SVD;
  ceres::Covariance covariance(cov_options);
  ASSERT_TRUE(covariance.Compute(std::vector<const double*>{ambient, ks, log_n}, &problem));
  double block[9], n_block[1];
  const double var = f.sigma * f.sigma;
  covariance.GetCovarianceBlock(ks, ks, block);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(f.ks_se[i], std::sqrt(var * block[4 * i]), 1e-6 * f.ks_se[i]);
  covariance.GetCovarianceBlock(ambient, ambient, block);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(f.ambient_se[i], std::sqrt(var * block[4 * i]), 1e-6 * f.ambient_se[i]);
  }
  covariance.GetCovarianceBlock(log_n, log_n, n_block);
  EXPECT_NEAR(f.shininess_se, f.shininess * std::sqrt(var * n_block[0]), 1e-6 * f.shininess_se);
}

TEST(FitMaterial, BadInputIsOneLine) {
  const reflectance::Material m = reflectance::FindMaterialPreset("plastic").material;
  Capture c = RenderSphere(m, Lobe::kPhong, Vec3d::Zero(), 0, 24);
  std::vector<Vec3d> normals = c.normals;
  normals.pop_back();
  EXPECT_THROW(FitMaterial(c.data, normals, {}), std::invalid_argument);
  normals = c.normals;
  normals[3] = Vec3d(NAN, 0, 1);
  try {
    FitMaterial(c.data, normals, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("not finite"), std::string::npos) << e.what();
  }
  // A normal map in another frame (z into the scene): named, not fitted as ambient light.
  normals = c.normals;
  for (Vec3d& n : normals) n.z() = -n.z();
  try {
    FitMaterial(c.data, normals, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("normals face away from the camera"), std::string::npos)
        << e.what();
  }
  std::fill(normals.begin(), normals.end(), Vec3d::Zero());
  EXPECT_THROW(FitMaterial(c.data, normals, {}), std::invalid_argument);
  // Three lights: Phong needs four.
  solve::PhotometricData three = c.data;
  three.images = 3;
  three.light_directions.resize(3);
  three.light_intensities.resize(3);
  three.values.clear();
  for (std::size_t p = 0; p < c.data.pixel_count(); ++p) {
    three.values.insert(three.values.end(), c.data.pixel(p), c.data.pixel(p) + 9);
  }
  try {
    FitMaterial(three, c.normals, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("needs at least 4"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace iphong::material
