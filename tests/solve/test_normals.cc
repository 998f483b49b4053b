// Normal recovery on renders with exact ground truth: round trips, noise, identifiability, bad
// input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "geometry/primitives.h"
#include "render/renderer.h"
#include "solve/internal.h"
#include "solve/metrics.h"
#include "solve/model_choice.h"
#include "solve/normals.h"
#include "solve/search.h"

namespace iphong::solve {
namespace {

using reflectance::Light;

struct Synthetic {
  render::Scene scene;
  render::RenderOutput out;
  PhotometricData data;
};

// A sphere under `lights` hemisphere lights (or a ring of them at 45° elevation), rendered per
// light (no ambient unless given) with the Phong lobe or `lobe`.
Synthetic MakeSphereData(const reflectance::Material& material, int lights, double noise_sigma,
                         const Vec3d& ambient = Vec3d::Zero(), int size = 96, bool ring = false,
                         reflectance::Lobe lobe = reflectance::Lobe::kPhong) {
  Synthetic s;
  s.scene.camera = geometry::Camera::Orthographic(size, size, 2.0);
  s.scene.lighting.ambient = ambient;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < lights; ++i) {
    const double z = ring ? std::sqrt(0.5) : 1 - 0.5 * (i + 0.5) / lights, r = std::sqrt(1 - z * z),
                 a = ring ? 2 * M_PI * i / lights : golden * i;
    s.scene.lighting.lights.push_back(
        Light::Directional(Vec3d(r * std::cos(a), r * std::sin(a), z), Vec3d(1.0, 0.9, 0.8)));
  }
  render::SceneObject sphere;
  sphere.mesh = geometry::MakeSphere(0.9, 6);
  sphere.material = material;
  s.scene.objects.push_back(sphere);
  render::RenderOptions options;
  options.model.lobe = lobe;
  options.noise.gaussian_sigma = noise_sigma;
  options.noise.seed = 3;
  s.out = render::Render(s.scene, options, true);
  std::vector<const float*> images;
  std::vector<Vec3d> dirs, intensities;
  for (std::size_t j = 0; j < s.out.per_light.size(); ++j) {
    images.push_back(s.out.per_light[j].pixels.data());
    dirs.push_back(s.scene.lighting.lights[j].direction_cam);
    intensities.push_back(s.scene.lighting.lights[j].diffuse_intensity);
  }
  s.data = GatherObservations(images, size, size, s.out.mask, dirs, intensities);
  return s;
}

// Two balls side by side (left at x = −1, right at x = 1) in a 160×80 view under 24 white
// hemisphere lights.
Synthetic MakeTwoBallsData(const reflectance::Material& left, const reflectance::Material& right) {
  Synthetic s;
  s.scene.camera = geometry::Camera::Orthographic(160, 80, 4.0);
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < 24; ++i) {
    const double z = 1 - 0.5 * (i + 0.5) / 24, r = std::sqrt(1 - z * z);
    s.scene.lighting.lights.push_back(Light::Directional(
        Vec3d(r * std::cos(golden * i), r * std::sin(golden * i), z), Vec3d::Ones()));
  }
  for (const auto& [material, x] : {std::pair{left, -1.0}, std::pair{right, 1.0}}) {
    render::SceneObject ball;
    ball.mesh = geometry::MakeSphere(0.9, 5);
    geometry::TransformMesh(ball.mesh, Eigen::Affine3d(Eigen::Translation3d(x, 0, 0)));
    ball.material = material;
    s.scene.objects.push_back(ball);
  }
  s.out = render::Render(s.scene, render::RenderOptions{}, true);
  std::vector<const float*> images;
  std::vector<Vec3d> dirs;
  for (std::size_t j = 0; j < s.out.per_light.size(); ++j) {
    images.push_back(s.out.per_light[j].pixels.data());
    dirs.push_back(s.scene.lighting.lights[j].direction_cam);
  }
  s.data = GatherObservations(images, 160, 80, s.out.mask, dirs,
                              std::vector<Vec3d>(dirs.size(), Vec3d::Ones()));
  return s;
}

reflectance::Material Plastic() {
  reflectance::Material m;
  m.ka = Vec3d::Constant(0.02);
  m.kd = Vec3d(0.7, 0.5, 0.3);
  m.ks = Vec3d::Constant(0.4);
  m.shininess = 20;
  return m;
}

NormalOptions Known(const reflectance::Material& m, const Vec3d& ambient) {
  NormalOptions o;
  o.material_known = true;
  o.ambient_term = ambient.cwiseProduct(m.ka);
  o.ks = m.ks;
  o.shininess = m.shininess;
  return o;
}

TEST(Normals, RoundTripWithKnownCoefficientsIsExact) {
  const auto m = Plastic();
  const Synthetic s = MakeSphereData(m, 24, 0.0, Vec3d::Ones());
  const NormalResult r = EstimateNormals(s.data, Known(m, Vec3d::Ones()));
  const AngularErrorMetrics e = CompareNormals(r.normals, s.out.normal_cam, s.out.mask);
  RecordProperty("mean_error_deg", std::to_string(e.mean_deg));
  EXPECT_LE(e.mean_deg, 0.01);
  EXPECT_LE(e.median_deg, 0.01);
  for (std::size_t p = 0; p < s.out.mask.inside.size(); p += 13) {
    if (!s.out.mask.inside[p]) continue;
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(r.albedo.pixels[3 * p + c], m.kd[c], 2e-3);
  }
  EXPECT_EQ(r.summary.dark_pixels, 0u);
}

TEST(Normals, BlinnPhongRoundTripToo) {
  auto m = Plastic();
  m.shininess = 60;
  Synthetic s;
  {
    // Render with the Blinn-Phong lobe.
    s = MakeSphereData(m, 20, 0.0);
    render::RenderOptions options;
    options.model.lobe = reflectance::Lobe::kBlinnPhong;
    s.out = render::Render(s.scene, options, true);
    std::vector<const float*> images;
    for (const ImageF& image : s.out.per_light) images.push_back(image.pixels.data());
    s.data = GatherObservations(images, 96, 96, s.out.mask, s.data.light_directions,
                                s.data.light_intensities);
  }
  NormalOptions o = Known(m, Vec3d::Zero());
  o.model = reflectance::Lobe::kBlinnPhong;
  const AngularErrorMetrics e =
      CompareNormals(EstimateNormals(s.data, o).normals, s.out.normal_cam, s.out.mask);
  EXPECT_LE(e.mean_deg, 0.01);
}

TEST(Normals, ChoosesTheLobeAndEstimatesKsAndAmbient) {
  const auto m = Plastic();
  const Synthetic s = MakeSphereData(m, 24, 0.0, Vec3d::Ones());
  NormalOptions o;  // nothing known
  const NormalResult r = EstimateNormals(s.data, o);
  EXPECT_TRUE(r.material_estimated);
  EXPECT_EQ(r.model, reflectance::Lobe::kPhong);
  // The golden-section search of log n stops within 4 % (model_choice.h).
  EXPECT_NEAR(r.shininess / 20, 1.0, 0.05);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.ambient_term[c], 0.02, 0.005);
  const AngularErrorMetrics e = CompareNormals(r.normals, s.out.normal_cam, s.out.mask);
  RecordProperty("mean_error_deg", std::to_string(e.mean_deg));
  EXPECT_LT(e.mean_deg, 0.5);
  // Lambertian fitting of the same images is clearly worse: highlights bias it.
  NormalOptions lambert;
  lambert.model = reflectance::Lobe::kLambert;
  const AngularErrorMetrics w =
      CompareNormals(EstimateNormals(s.data, lambert).normals, s.out.normal_cam, s.out.mask);
  EXPECT_GT(w.mean_deg, 3 * e.mean_deg);
}

// The model choice's sample covers a whole-frame capture: an even stride of 96 through 240×240
// pixels in raster order visits 5 columns; the golden-ratio sequence visits most of them.
TEST(Normals, ModelChoiceSampleIsSpreadOverRowsAndColumns) {
  const std::vector<std::size_t> sample = SpreadIndices(240 * 240, 600);
  ASSERT_EQ(sample.size(), 600u);
  EXPECT_TRUE(std::is_sorted(sample.begin(), sample.end()));
  std::vector<int> columns(240, 0), rows(240, 0);
  for (const std::size_t p : sample) {
    ASSERT_LT(p, 240u * 240u);
    columns[p % 240] = 1, rows[p / 240] = 1;
  }
  EXPECT_GT(std::accumulate(columns.begin(), columns.end(), 0), 200);
  EXPECT_GT(std::accumulate(rows.begin(), rows.end(), 0), 200);
  EXPECT_EQ(SpreadIndices(7, 600), (std::vector<std::size_t>{0, 1, 2, 3, 4, 5, 6}));
}

// The held-out test predicts from each fold's normal refined off the search's grid: from the
// grid's normals (up to ~2° off) a sharp lobe loses to a broader one for that alone, and a
// noise-free Phong n 30 came back as 38.6 (the median pixel 0.27° off instead of exact).
TEST(Normals, UnknownShininessComesBackExactlyFromNoiseFreeImages) {
  for (const auto& [lobe, shininess] : {std::pair{reflectance::Lobe::kPhong, 30.0},
                                        std::pair{reflectance::Lobe::kBlinnPhong, 90.0}}) {
    reflectance::Material m = Plastic();
    m.ka = Vec3d::Zero();
    m.shininess = shininess;
    const Synthetic s = MakeSphereData(m, 48, 0.0, Vec3d::Zero(), 96, false, lobe);
    const NormalResult r = EstimateNormals(s.data, NormalOptions{});
    EXPECT_EQ(r.model, lobe);
    // The golden-section search of log n stops within 4 %.
    EXPECT_NEAR(r.shininess / shininess, 1.0, 0.05) << reflectance::LobeName(lobe);
    const AngularErrorMetrics e = CompareNormals(r.normals, s.out.normal_cam, s.out.mask);
    RecordProperty(reflectance::LobeName(lobe) + "_shininess", std::to_string(r.shininess));
    RecordProperty(reflectance::LobeName(lobe) + "_mean_deg", std::to_string(e.mean_deg));
    EXPECT_LT(e.median_deg, 0.02) << reflectance::LobeName(lobe);
    EXPECT_LT(e.mean_deg, 0.1) << reflectance::LobeName(lobe);
  }
}

// The ambient term is in the model of every image; unknown, it is estimated from the pixels that
// see a light from behind and kept only where it predicts held-out observations better.
TEST(Normals, UnknownAmbientOfAnyStrength) {
  reflectance::Material m = Plastic();
  m.ka = Vec3d(0.1, 0.1, 0.1);
  std::string table;
  for (const double ambient : {0.0, 0.2, 0.5, 1.0}) {
    const Synthetic s = MakeSphereData(m, 24, 0.0, Vec3d::Constant(ambient));
    const NormalResult r = EstimateNormals(s.data, NormalOptions{});
    const double e = CompareNormals(r.normals, s.out.normal_cam, s.out.mask).mean_deg;
    table += " Ia " + std::to_string(ambient) + ": " + std::to_string(e) + " deg;";
    // 0.027, 0.028, 0.028, 0.031 measured (0.13, 0.14, 0.15, 0.18 when the held-out folds
    // predicted from grid normals, and 0.13, 0.10, 0.11, 0.40 when the lobe was chosen before the
    // ambient term).
    EXPECT_LT(e, 0.1) << "ambient " << ambient;
    EXPECT_NEAR(r.ambient_term[0], 0.1 * ambient, 0.01) << "ambient " << ambient;
  }
  RecordProperty("ambient_table", table);
}

// Twelve lights on one ring: halves of six cannot test a specular model (each lost to Lambert and
// the sphere came out 1.4–1.7° off); leave-one-out folds can.
TEST(Normals, FewLightsAreCrossValidatedLeavingOneOut) {
  EXPECT_EQ(FoldCount(96), 2);
  EXPECT_EQ(FoldCount(40), 3);
  EXPECT_EQ(FoldCount(24), 24);
  EXPECT_EQ(FoldCount(12), 12);
  reflectance::Material m = Plastic();
  m.ka = Vec3d::Constant(0.1);
  std::string table;
  for (const double ambient : {0.0, 0.2, 0.5, 1.0}) {
    const Synthetic s = MakeSphereData(m, 12, 0.0, Vec3d::Constant(ambient), 96, true);
    const NormalResult r = EstimateNormals(s.data, NormalOptions{});
    const double e = CompareNormals(r.normals, s.out.normal_cam, s.out.mask).mean_deg;
    table += " Ia " + std::to_string(ambient) + ": " + std::to_string(e) + " deg;";
    EXPECT_NE(r.model, reflectance::Lobe::kLambert) << "ambient " << ambient;
    // 0.070, 0.040, 0.070, 0.074 measured; 0.21, 0.22, 0.21, 0.23 from grid normals; 0.21, 0.22,
    // 0.14, 0.66 when the lobe was chosen before the ambient term (at Ia 1 the broadest lobe
    // imitated it).
    EXPECT_LT(e, 0.1) << "ambient " << ambient;
    EXPECT_NEAR(r.ambient_term[0], 0.1 * ambient, 0.01) << "ambient " << ambient;
  }
  RecordProperty("ring_table", table);
}

TEST(Normals, IntegerCodesAreRecognized) {
  PhotometricData d;
  d.images = 1;
  d.values = {0.0f, 1 / 255.0f, 0.5f + 0.5f / 255, 1.0f, 37 / 255.0f, 254 / 255.0f};
  EXPECT_DOUBLE_EQ(IntegerCodeStep(d), 1 / 255.0);
  d.values = {0.0f, 1 / 65535.0f, 30001 / 65535.0f, 65534 / 65535.0f, 1.0f, 16384 / 65535.0f};
  EXPECT_DOUBLE_EQ(IntegerCodeStep(d), 1 / 65535.0);
  d.values = {0.0f, 1 / 1023.0f, 700 / 1023.0f};
  EXPECT_DOUBLE_EQ(IntegerCodeStep(d), 1 / 1023.0);
  // Floats, and 8-bit sRGB codes decoded to linear values, are not codes (a few values may be
  // near one by chance, not a whole image's).
  d.values.clear();
  for (int i = 0; i < 100; ++i) d.values.push_back(static_cast<float>(0.01 * i + 0.00123 * i * i));
  EXPECT_EQ(IntegerCodeStep(d), 0.0);
  d.values.clear();
  for (int k = 0; k < 256; k += 3) {
    const double v = k / 255.0;
    d.values.push_back(
        static_cast<float>(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4)));
  }
  EXPECT_EQ(IntegerCodeStep(d), 0.0);
}

// 8-bit images made by truncating (code k for a value in [k, k + 1)), as a conversion that
// drops the low byte of 16-bit data does: on average half a code darker, a bias that grows to
// tens of percent in the dark observations that decide the normal near the terminator. The plan
// finds it by held-out prediction and takes each nonzero code at the middle of its interval;
// rounded codes it leaves as they are.
TEST(Normals, TruncatedIntegerCodesAreTakenAtTheirMiddle) {
  // Dim, as DiLiGenT's 8-bit crops are (their median code is 12 to 17): kd 0.08 is 20 codes.
  reflectance::Material dim;
  dim.kd = Vec3d(0.08, 0.07, 0.06);
  dim.ks = Vec3d::Constant(0.5);
  dim.shininess = 50;
  // 96 lights, as DiLiGenT has: with 48 the held-out choice did not tell the two apart (the
  // codes were then taken as recorded, as before).
  const Synthetic s = MakeSphereData(dim, 96, 0.0, Vec3d::Zero(), 64);
  const auto quantized = [&](bool truncate) {
    PhotometricData q = s.data;
    for (float& v : q.values) {
      const double code = std::clamp(v * 255.0, 0.0, 255.0);
      v = static_cast<float>((truncate ? std::floor(code) : std::round(code)) / 255);
    }
    return q;
  };
  const PhotometricData truncated = quantized(true);
  NormalPlan plan = PlanNormals(truncated, NormalOptions{});
  EXPECT_DOUBLE_EQ(plan.model_choice.code_step, 1 / 255.0);
  EXPECT_DOUBLE_EQ(plan.options.code_offset, 0.5 / 255);
  EXPECT_EQ(PlanNormals(quantized(false), NormalOptions{}).options.code_offset, 0.0);
  // With the model the plan chose, against the same codes taken as they are.
  const auto error = [&](const NormalPlan& p) {
    return CompareNormals(SolveNormalsWithPlan(truncated, p).normals, s.out.normal_cam, s.out.mask)
        .mean_deg;
  };
  const double middle = error(plan);
  plan.options.code_offset = 0;
  const double as_recorded = error(plan);
  std::printf("truncated 8-bit codes: %.3f deg at their middle, %.3f deg as recorded\n", middle,
              as_recorded);
  EXPECT_LT(middle, 0.7 * as_recorded);
}

// Two balls of different materials side by side: ks is free per pixel, so one shininess serves
// both and each ball's ks is read off the specular map.
TEST(Normals, KsPerPixelFollowsTwoMaterials) {
  reflectance::Material red, blue;
  red.kd = Vec3d(0.7, 0.15, 0.1), red.ks = Vec3d::Constant(0.5), red.shininess = 20;
  blue.kd = Vec3d(0.1, 0.3, 0.6), blue.ks = Vec3d::Constant(0.15), blue.shininess = 20;
  const Synthetic s = MakeTwoBallsData(red, blue);
  const NormalResult r = EstimateNormals(s.data, NormalOptions{});
  const double e = CompareNormals(r.normals, s.out.normal_cam, s.out.mask).mean_deg;
  RecordProperty("mean_error_deg", std::to_string(e));
  EXPECT_LT(e, 0.3);
  ASSERT_EQ(r.specular.width, 160);
  // Each ball's ks at its centre and halfway to its rim: in the ratio of the truth (one shininess
  // for both, chosen by held-out prediction: its small error moves the two scales apart a little).
  for (const int dx : {0, 18}) {
    const std::size_t red_p = 40 * 160 + 40 + dx, blue_p = 40 * 160 + 120 + dx;
    ASSERT_TRUE(s.out.mask.inside[red_p] && s.out.mask.inside[blue_p]);
    const double ratio = r.specular.pixels[3 * red_p + 1] / r.specular.pixels[3 * blue_p + 1];
    EXPECT_NEAR(ratio, 0.5 / 0.15, 0.3 * 0.5 / 0.15) << dx;  // 3.8 and 4.1 measured
  }
}

// A matte ball beside a glossy one: the object's model is specular, but each pixel keeps it only
// where it predicts the pixel's own held-out lights better than Lambert.
TEST(Normals, EachPixelKeepsTheSpecularModelOnlyWhereItPredictsBetter) {
  reflectance::Material glossy, matte;
  glossy.kd = matte.kd = Vec3d(0.5, 0.4, 0.3);
  glossy.ks = Vec3d::Constant(0.5);
  glossy.shininess = 20;
  const Synthetic s = MakeTwoBallsData(glossy, matte);
  const NormalResult r = EstimateNormals(s.data, NormalOptions{});
  ASSERT_NE(r.model, reflectance::Lobe::kLambert);
  ASSERT_EQ(r.model_map.width, 160);
  // Counted over each ball's disc.
  double specular[2] = {0, 0}, count[2] = {0, 0};
  for (int y = 0; y < 80; ++y) {
    for (int x = 0; x < 160; ++x) {
      const float v = r.model_map.pixels[y * 160 + x];
      if (v < 0) continue;
      specular[x >= 80] += v;
      count[x >= 80] += 1;
    }
  }
  const double glossy_share = specular[0] / count[0], matte_share = specular[1] / count[1];
  RecordProperty("glossy_share", std::to_string(glossy_share));
  RecordProperty("matte_share", std::to_string(matte_share));
  EXPECT_LT(matte_share, 0.2);
  EXPECT_GT(glossy_share, 0.3);  // the lobe shows on part of the ball only
  EXPECT_LT(CompareNormals(r.normals, s.out.normal_cam, s.out.mask).mean_deg, 0.3);
  NormalOptions object_wide;
  object_wide.per_pixel_model = false;
  EXPECT_TRUE(EstimateNormals(s.data, object_wide).model_map.pixels.empty());
}

// Metallic: the highlight takes the surface colour. Found as it is, because each channel's ks is
// free.
TEST(Normals, MetallicHighlightsTakeTheSurfaceColour) {
  reflectance::Material gold;
  gold.kd = Vec3d(0.3, 0.2, 0.05);
  gold.ks = Vec3d(0.6, 0.4, 0.1);
  gold.shininess = 20;
  const Synthetic s = MakeSphereData(gold, 24, 0.0);
  const NormalResult r = EstimateNormals(s.data, NormalOptions{});
  EXPECT_LT(CompareNormals(r.normals, s.out.normal_cam, s.out.mask).mean_deg, 0.6);
  EXPECT_GT(r.ks[0], 2.5 * r.ks[2]);  // the colour of the median ks
}

TEST(Normals, ErrorGrowsSmoothlyWithNoise) {
  const auto m = Plastic();
  double previous = -1;
  std::string table;
  for (double sigma : {0.0, 0.0025, 0.005, 0.01, 0.02}) {
    const Synthetic s = MakeSphereData(m, 24, sigma);
    const AngularErrorMetrics e = CompareNormals(
        EstimateNormals(s.data, Known(m, Vec3d::Zero())).normals, s.out.normal_cam, s.out.mask);
    table += " sigma " + std::to_string(sigma) + ": " + std::to_string(e.mean_deg) + " deg;";
    EXPECT_GT(e.mean_deg, previous);
    // Roughly linear in sigma: the error per unit of noise stays bounded (about 30 deg per unit).
    if (sigma > 0) {
      EXPECT_LT(e.mean_deg / sigma, 60.0) << "sigma " << sigma;
    }
    previous = e.mean_deg;
  }
  RecordProperty("noise_table", table);
  std::printf("noise sweep:%s\n", table.c_str());
}

// Red albedo under a broad white lobe, 12 lights: highlights pull Woodham's start into a wrong
// basin for a few percent of the pixels (4% ended more than 10° off when the fit started there).
// The global search starts every pixel in the right one: no pixel is off by more than 0.1°.
TEST(Normals, GlobalSearchLeavesNoPixelInAWrongBasin) {
  reflectance::Material red;
  red.kd = Vec3d(0.9, 0.2, 0.1);
  red.ks = Vec3d(0.5, 0.5, 0.4);
  red.shininess = 10;
  const Synthetic s = MakeSphereData(red, 12, 0.0, Vec3d::Zero(), 128);
  const AngularErrorMetrics e = CompareNormals(
      EstimateNormals(s.data, Known(red, Vec3d::Zero())).normals, s.out.normal_cam, s.out.mask);
  double worst = 0;
  for (std::size_t p = 0; p < s.out.mask.inside.size(); ++p) {
    if (s.out.mask.inside[p]) worst = std::max<double>(worst, e.error_deg.pixels[p]);
  }
  RecordProperty("mean_deg", std::to_string(e.mean_deg));
  RecordProperty("worst_deg", std::to_string(worst));
  EXPECT_LT(e.mean_deg, 0.01);
  EXPECT_LT(worst, 0.1);
}

// A search takes its sums from the table (over every light, or a fold's training lights) less
// the few lights it leaves out; it must choose what summing over its usable lights directly does.
// Pixels of a Phong sphere with a fold held out, some lights saturated, or both.
TEST(Normals, SearchSumsFromFoldTablesEqualDirectSums) {
  const Synthetic s = MakeSphereData(Plastic(), 48, 0.002);
  std::vector<int> fold(48);
  for (int j = 0; j < 48; ++j) fold[j] = (j * 7) % 3;
  reflectance::ModelOptions model;
  const CandidateTable with_folds(s.data.light_directions, model, 20, 1000, fold);
  const CandidateTable plain(s.data.light_directions, model, 20, 1000);
  ASSERT_EQ(with_folds.folds(), 3);
  ASSERT_EQ(plain.folds(), 0);
  NormalSearch a(with_folds), b(plain);
  std::vector<double> y(48), usable(48);
  int compared = 0;
  for (std::size_t p = 0; p < s.data.pixel_count(); p += 37) {
    const float* obs = s.data.pixel(p);
    for (int j = 0; j < 48; ++j) {
      y[j] = internal::Luminance(Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]));
    }
    for (int held_out = -1; held_out < 3; ++held_out) {
      for (const bool saturated : {false, true}) {
        for (int j = 0; j < 48; ++j) {
          usable[j] = fold[j] == held_out || (saturated && (j + p) % 11 == 0) ? 0.0 : 1.0;
        }
        const SearchResult x = a.Search(y.data(), usable.data(), 0.01, nullptr);
        const SearchResult z = b.Search(y.data(), usable.data(), 0.01, nullptr);
        ASSERT_EQ(x.candidate, z.candidate) << "pixel " << p << " fold " << held_out;
        ASSERT_NEAR(x.cost, z.cost, 1e-9 + 1e-6 * z.cost);
        ASSERT_NEAR(x.kd, z.kd, 1e-6 * (1 + z.kd));
        ASSERT_NEAR(x.ks, z.ks, 1e-6 * (1 + z.ks));
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 1000);
}

// Each fine candidate of the search's table belongs to its nearest coarse direction, exactly as
// comparing it with every coarse direction finds (the table compares only a band of z).
TEST(Normals, CandidateTableGroupsEachDirectionWithItsNearestCoarseOne) {
  const std::vector<Vec3d> lights = {Vec3d(0, 0, 1), Vec3d(0.6, 0, 0.8), Vec3d(0, 0.6, 0.8)};
  for (int count : {16, 100, 1000, 4097, 16384}) {
    const CandidateTable table(lights, reflectance::ModelOptions{}, 10, count);
    const std::vector<Vec3d> coarse = HemisphereDirections(std::max(4, count / 4));
    ASSERT_EQ(table.size(), count + static_cast<int>(coarse.size()));
    std::vector<int> owner(count, -1);
    for (int c = table.fine_count(); c < table.size(); ++c) {
      for (int f : table.members(c)) owner[f] = c - table.fine_count();
    }
    for (int f = 0; f < count; ++f) {
      const Vec3d& n = table.normal(f);
      int nearest = 0;
      for (int c = 1; c < static_cast<int>(coarse.size()); ++c)
        if (coarse[c].dot(n) > coarse[nearest].dot(n)) nearest = c;
      ASSERT_EQ(owner[f], nearest) << "count " << count << ", fine direction " << f;
    }
  }
}

// A ball above a floor: the floor sees the ball's cast shadow under several lights. Censored,
// a shadowed observation says only "less light arrived" and the floor stays flat; fitted as an
// ordinary observation (a threshold so large nothing is censored) it tilts the floor's normals.
TEST(Normals, CastShadowsAreCensoredNotFitted) {
  render::Scene scene;
  scene.camera = geometry::Camera::Orthographic(96, 96, 3.0);
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < 24; ++i) {
    const double z = 1 - 0.6 * (i + 0.5) / 24, r = std::sqrt(1 - z * z);
    scene.lighting.lights.push_back(Light::Directional(
        Vec3d(r * std::cos(golden * i), r * std::sin(golden * i), z), Vec3d::Ones()));
  }
  reflectance::Material matte;
  matte.kd = Vec3d(0.6, 0.6, 0.6);
  render::SceneObject floor, ball;
  floor.mesh = geometry::MakeHeightField(geometry::BumpRipples{0, 0.4, 0, 1}, 3.2, 3.2, 60, 60);
  floor.material = matte;
  ball.mesh = geometry::MakeSphere(0.6, 5);
  geometry::TransformMesh(ball.mesh, Eigen::Affine3d(Eigen::Translation3d(0, 0, 0.9)));
  ball.material = matte;
  scene.objects = {floor, ball};
  render::RenderOptions options;
  options.shadows = true;
  const render::RenderOutput out = render::Render(scene, options, true);
  std::vector<const float*> images;
  std::vector<Vec3d> dirs;
  for (std::size_t j = 0; j < out.per_light.size(); ++j) {
    images.push_back(out.per_light[j].pixels.data());
    dirs.push_back(scene.lighting.lights[j].direction_cam);
  }
  const PhotometricData data = GatherObservations(images, 96, 96, out.mask, dirs,
                                                  std::vector<Vec3d>(dirs.size(), Vec3d::Ones()));
  // The floor: pixels whose true normal is the view axis, outside the ball's silhouette.
  Mask floor_mask = out.mask;
  for (std::size_t p = 0; p < floor_mask.inside.size(); ++p) {
    floor_mask.inside[p] =
        floor_mask.inside[p] && out.normal_cam.pixels[3 * p + 2] > 0.9999f &&
        std::hypot(static_cast<double>(p % 96) - 47.5, static_cast<double>(p / 96) - 47.5) > 22;
  }
  ASSERT_GT(floor_mask.count(), 3000u);
  NormalOptions censored = Known(matte, Vec3d::Zero());
  NormalOptions fitted = censored;
  fitted.shadow_threshold = 1e6;
  const double e_censored =
      CompareNormals(EstimateNormals(data, censored).normals, out.normal_cam, floor_mask).mean_deg;
  const double e_fitted =
      CompareNormals(EstimateNormals(data, fitted).normals, out.normal_cam, floor_mask).mean_deg;
  RecordProperty("censored_deg", std::to_string(e_censored));
  RecordProperty("fitted_deg", std::to_string(e_fitted));
  EXPECT_LT(e_censored, 0.1);
  EXPECT_GT(e_fitted, 5 * e_censored);
}

TEST(Normals, MatteObjectsChooseLambert) {
  reflectance::Material matte;
  matte.kd = Vec3d(0.6, 0.6, 0.6);
  const Synthetic s = MakeSphereData(matte, 16, 0.0);
  const NormalResult r = EstimateNormals(s.data, NormalOptions{});
  EXPECT_EQ(r.model, reflectance::Lobe::kLambert);
  EXPECT_FALSE(r.material_estimated);
  EXPECT_FALSE(r.specular_identifiable);
  EXPECT_NE(r.specular_note.find("Lambert"), std::string::npos);
  EXPECT_LT(CompareNormals(r.normals, s.out.normal_cam, s.out.mask).mean_deg, 0.05);
}

TEST(Normals, WoodhamIsExactWhereEveryLightIsSeen) {
  // A gentle bump lit from near the view axis: no attached shadows, pure Lambert.
  render::Scene scene;
  scene.camera = geometry::Camera::Orthographic(64, 64, 2.0);
  for (const Vec3d& d :
       {Vec3d(0.2, 0.1, 1), Vec3d(-0.2, 0.15, 1), Vec3d(0.05, -0.25, 1), Vec3d(-0.1, -0.1, 1)}) {
    scene.lighting.lights.push_back(Light::Directional(d, Vec3d::Ones()));
  }
  render::SceneObject bump;
  bump.mesh = geometry::MakeHeightField(geometry::BumpRipples{0.2, 0.4, 0, 1}, 2.2, 2.2, 200, 200);
  bump.material.kd = Vec3d(0.5, 0.6, 0.7);
  scene.objects.push_back(bump);
  const render::RenderOutput out = render::Render(scene, render::RenderOptions{}, true);
  std::vector<const float*> images;
  std::vector<Vec3d> dirs, intensities;
  for (std::size_t j = 0; j < 4; ++j) {
    images.push_back(out.per_light[j].pixels.data());
    dirs.push_back(scene.lighting.lights[j].direction_cam);
    intensities.push_back(Vec3d::Ones());
  }
  NormalOptions o;
  o.model = reflectance::Lobe::kLambert;
  o.discard_dark = o.discard_bright = 0;
  const NormalResult r =
      EstimateNormals(GatherObservations(images, 64, 64, out.mask, dirs, intensities), o);
  EXPECT_LT(CompareNormals(r.normals, out.normal_cam, out.mask).mean_deg, 1e-3);
}

TEST(Normals, PixelsDarkInEveryImageAreFlaggedNotNan) {
  const auto m = Plastic();
  Synthetic s = MakeSphereData(m, 8, 0.0, Vec3d::Zero(), 48);
  for (int j = 0; j < s.data.images; ++j)
    for (int c = 0; c < 3; ++c) s.data.values[(0 * s.data.images + j) * 3 + c] = 0;  // pixel 0
  const NormalResult r = EstimateNormals(s.data, Known(m, Vec3d::Zero()));
  EXPECT_EQ(r.summary.dark_pixels, 1u);
  const std::size_t p = s.data.pixels[0];
  EXPECT_EQ(r.residual.pixels[p], -1.0f);
  EXPECT_EQ(r.normals.pixels[3 * p + 2], 1.0f);
  for (float v : r.normals.pixels) ASSERT_TRUE(std::isfinite(v));
  for (float v : r.albedo.pixels) ASSERT_TRUE(std::isfinite(v));
}

TEST(Normals, BadInputGivesOneLineMessages) {
  const auto m = Plastic();
  Synthetic s = MakeSphereData(m, 4, 0.0, Vec3d::Zero(), 24);
  auto message = [&](const PhotometricData& d, const NormalOptions& o) {
    try {
      EstimateNormals(d, o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  PhotometricData two = s.data;
  two.images = 2;
  two.light_directions.resize(2);
  two.light_intensities.resize(2);
  two.values.resize(two.pixels.size() * 2 * 3);
  EXPECT_EQ(message(two, NormalOptions{}),
            "per-pixel photometric stereo needs at least 3 images, got 2");
  // RecoverNormals takes two images to the global solver, which needs the albedo.
  try {
    RecoverNormals(two, NormalOptions{});
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "with 2 image(s) the coefficients must be known, kd (a uniform albedo) included");
  }
  PhotometricData lights = s.data;
  lights.light_directions.pop_back();
  EXPECT_EQ(message(lights, NormalOptions{}), "4 images but 3 light directions and 4 intensities");
  PhotometricData zero = s.data;
  zero.light_intensities[2] = Vec3d(1, 0, 1);
  EXPECT_EQ(message(zero, NormalOptions{}), "light intensity 3 must be finite and > 0");
  NormalOptions bad;
  bad.discard_dark = 0.7;
  bad.discard_bright = 0.4;
  EXPECT_EQ(message(s.data, bad), "discard fractions must be >= 0 and sum to less than 1");
  NormalOptions no_threshold;
  no_threshold.shadow_threshold = 0;
  EXPECT_EQ(message(s.data, no_threshold), "shadow threshold must be > 0");
  // Images: NaN and size mismatches are caught when gathering.
  ImageF image(24, 24, 3, 0.5f);
  image.pixels[5] = std::nanf("");
  std::vector<const float*> images(3, image.pixels.data());
  std::vector<Vec3d> dirs(3, Vec3d(0, 0, 1)), intensities(3, Vec3d::Ones());
  EXPECT_THROW(GatherObservations(images, 24, 24, Mask(24, 24, true), dirs, intensities),
               std::invalid_argument);
  EXPECT_THROW(GatherObservations(images, 24, 24, Mask(20, 24, true), dirs, intensities),
               std::invalid_argument);
}

TEST(Metrics, KnownAnglesAndFractions) {
  ImageF gt(4, 1, 3), est(4, 1, 3);
  const double angles[4] = {1, 7, 15, 30};
  for (int i = 0; i < 4; ++i) {
    const double a = angles[i] * M_PI / 180;
    gt.pixels[3 * i + 2] = 1;
    est.pixels[3 * i] = static_cast<float>(std::sin(a));
    est.pixels[3 * i + 2] = static_cast<float>(std::cos(a));
  }
  const AngularErrorMetrics m = CompareNormals(est, gt, Mask(4, 1, true));
  EXPECT_EQ(m.pixels, 4u);
  EXPECT_NEAR(m.mean_deg, (1 + 7 + 15 + 30) / 4.0, 1e-5);
  EXPECT_NEAR(m.median_deg, 11.0, 1e-5);
  EXPECT_DOUBLE_EQ(m.below_5_deg, 0.25);
  EXPECT_DOUBLE_EQ(m.below_10_deg, 0.5);
  EXPECT_DOUBLE_EQ(m.below_20_deg, 0.75);
  EXPECT_NEAR(m.error_deg.pixels[3], 30, 1e-5);
}

}  // namespace
}  // namespace iphong::solve
