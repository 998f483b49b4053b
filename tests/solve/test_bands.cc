// Normal recovery in bands of rows (bands.h) against the same recovery in one piece: the plan
// sample, the plan and every pixel must come out bit for bit the same, whatever the band height.
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/primitives.h"
#include "render/renderer.h"
#include "solve/bands.h"
#include "solve/normals.h"

namespace iphong::solve {
namespace {

// A noisy plastic sphere under 32 lights with ambient light, every coefficient unknown.
struct Capture {
  render::RenderOutput out;
  std::vector<Vec3d> directions, intensities;
  int size = 40;
};

Capture MakeCapture() {
  Capture c;
  render::Scene scene;
  scene.camera = geometry::Camera::Orthographic(c.size, c.size, 2.0);
  scene.lighting.ambient = Vec3d::Constant(0.5);
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < 32; ++i) {
    const double z = 1 - 0.6 * (i + 0.5) / 32, r = std::sqrt(1 - z * z);
    scene.lighting.lights.push_back(reflectance::Light::Directional(
        Vec3d(r * std::cos(golden * i), r * std::sin(golden * i), z), Vec3d(1.0, 0.9, 0.8)));
    c.directions.push_back(scene.lighting.lights.back().direction_cam);
    c.intensities.push_back(scene.lighting.lights.back().diffuse_intensity);
  }
  render::SceneObject sphere;
  sphere.mesh = geometry::MakeSphere(0.9, 5);
  sphere.material.ka = Vec3d::Constant(0.05);
  sphere.material.kd = Vec3d(0.6, 0.5, 0.4);
  sphere.material.ks = Vec3d::Constant(0.3);
  sphere.material.shininess = 30;
  scene.objects.push_back(sphere);
  render::RenderOptions options;
  options.noise.gaussian_sigma = 0.003;
  options.noise.seed = 11;
  c.out = render::Render(scene, options, true);
  return c;
}

// The observations of rows [y0, y1) of the capture, indexed within the band.
PhotometricData Band(const Capture& c, int y0, int y1) {
  const int w = c.size;
  Mask mask(w, y1 - y0, false);
  std::copy(c.out.mask.inside.begin() + static_cast<std::ptrdiff_t>(y0) * w,
            c.out.mask.inside.begin() + static_cast<std::ptrdiff_t>(y1) * w, mask.inside.begin());
  std::vector<const float*> images;
  for (const ImageF& image : c.out.per_light) images.push_back(image.at(0, y0));
  return GatherObservations(images, w, y1 - y0, mask, c.directions, c.intensities);
}

void ExpectRowsEqual(const ImageF& whole, int y0, const ImageF& band, const char* what) {
  if (whole.pixels.empty()) {
    EXPECT_TRUE(band.pixels.empty()) << what;
    return;
  }
  ASSERT_EQ(band.width, whole.width) << what;
  ASSERT_EQ(band.channels, whole.channels) << what;
  for (std::size_t i = 0; i < band.pixels.size(); ++i) {
    const float expected =
        whole.pixels[static_cast<std::size_t>(y0) * whole.width * whole.channels + i];
    ASSERT_EQ(band.pixels[i], expected) << what << " row " << y0 << " value " << i;
  }
}

class Bands : public ::testing::TestWithParam<std::pair<int, std::size_t>> {};

TEST_P(Bands, EqualTheWholeBitForBit) {
  const auto [band_rows, plan_sample] = GetParam();
  const Capture c = MakeCapture();
  NormalOptions options;
  options.plan_sample = plan_sample;  // below the pixel count: the sample is a stride subset
  const NormalResult whole = EstimateNormals(Band(c, 0, c.size), options);
  ASSERT_TRUE(whole.material_estimated);

  BandSource source;
  source.width = c.size;
  source.height = c.size;
  source.masked_pixels = c.out.mask.count();
  int reads = 0;
  source.read = [&](int y0, int y1, bool) {
    ++reads;
    return Band(c, y0, y1);
  };
  int written_rows = 0;
  const NormalResult banded =
      EstimateNormalsInBands(source, band_rows, options, [&](int y0, const NormalResult& band) {
        EXPECT_EQ(y0, written_rows);
        written_rows += band.normals.height;
        ExpectRowsEqual(whole.normals, y0, band.normals, "normals");
        ExpectRowsEqual(whole.albedo, y0, band.albedo, "albedo");
        ExpectRowsEqual(whole.specular, y0, band.specular, "specular");
        ExpectRowsEqual(whole.residual, y0, band.residual, "residual");
        ExpectRowsEqual(whole.model_map, y0, band.model_map, "model map");
      });
  EXPECT_EQ(written_rows, c.size);
  const int bands = (c.size + band_rows - 1) / band_rows;
  EXPECT_EQ(reads, 2 * bands);  // one pass for the sample, one for the fit
  EXPECT_EQ(banded.model, whole.model);
  EXPECT_EQ(banded.shininess, whole.shininess);
  EXPECT_EQ(banded.ambient_term, whole.ambient_term);
  EXPECT_EQ(banded.ks, whole.ks);
  EXPECT_EQ(banded.summary.pixels, whole.summary.pixels);
  EXPECT_EQ(banded.summary.iterations, whole.summary.iterations);
  EXPECT_EQ(banded.specular_note, whole.specular_note);
}

// Band heights that divide the image and that do not, one row, and the whole image at once; a
// plan sample of every pixel and of a stride subset.
INSTANTIATE_TEST_SUITE_P(Heights, Bands,
                         ::testing::Values(std::pair{1, std::size_t{131072}},
                                           std::pair{7, std::size_t{131072}},
                                           std::pair{18, std::size_t{300}},
                                           std::pair{40, std::size_t{300}}));

// Woodham and known coefficients decide nothing for the whole object: one pass, same maps.
TEST(Bands, WoodhamAndKnownCoefficientsReadOnce) {
  const Capture c = MakeCapture();
  NormalOptions lambert;
  lambert.model = reflectance::Lobe::kLambert;
  NormalOptions known;
  known.material_known = true;
  known.ks = Vec3d::Constant(0.3);
  known.shininess = 30;
  known.ambient_term = Vec3d::Constant(0.025);
  for (const NormalOptions& options : {lambert, known}) {
    const NormalResult whole = EstimateNormals(Band(c, 0, c.size), options);
    BandSource source;
    source.width = c.size;
    source.height = c.size;
    source.masked_pixels = c.out.mask.count();
    int reads = 0;
    source.read = [&](int y0, int y1, bool first_pass) {
      EXPECT_TRUE(first_pass);
      ++reads;
      return Band(c, y0, y1);
    };
    const NormalResult banded =
        EstimateNormalsInBands(source, 9, options, [&](int y0, const NormalResult& band) {
          ExpectRowsEqual(whole.normals, y0, band.normals, "normals");
          ExpectRowsEqual(whole.albedo, y0, band.albedo, "albedo");
        });
    EXPECT_EQ(reads, (c.size + 8) / 9);
    EXPECT_EQ(banded.ks, whole.ks);
  }
}

// Images identical at every pixel are refused in bands as in one piece, also where no plan sample
// is drawn (known coefficients: one pass, each band checked).
TEST(Bands, RefuseIdenticalImagesWithoutAPlanSample) {
  Capture c = MakeCapture();
  for (ImageF& image : c.out.per_light) image = c.out.per_light[0];
  NormalOptions known;
  known.material_known = true;
  known.ks = Vec3d::Constant(0.3);
  known.shininess = 30;
  std::string whole_error;
  try {
    EstimateNormals(Band(c, 0, c.size), known);
  } catch (const std::invalid_argument& e) {
    whole_error = e.what();
  }
  EXPECT_NE(whole_error.find("images are the same at each of the"), std::string::npos);
  BandSource source;
  source.width = c.size;
  source.height = c.size;
  source.masked_pixels = c.out.mask.count();
  source.read = [&](int y0, int y1, bool) { return Band(c, y0, y1); };
  std::string banded_error;
  try {
    EstimateNormalsInBands(source, 9, known, [](int, const NormalResult&) {});
  } catch (const std::invalid_argument& e) {
    banded_error = e.what();
  }
  EXPECT_EQ(banded_error, whole_error);
}

TEST(Bands, PlanSampleIsEvenAndComplete) {
  const std::vector<std::size_t> all = PlanSampleIndices(10, 131072);
  ASSERT_EQ(all.size(), 10u);
  for (std::size_t i = 0; i < all.size(); ++i) EXPECT_EQ(all[i], i);
  const std::vector<std::size_t> some = PlanSampleIndices(1000, 4);
  EXPECT_EQ(some, (std::vector<std::size_t>{0, 250, 500, 750}));
  // Far beyond 32 bits of pixels × sample the positions stay exact and inside.
  const std::vector<std::size_t> big = PlanSampleIndices(std::size_t{1} << 40, 3);
  EXPECT_EQ(big.back(), (std::size_t{2} << 40) / 3);
}

TEST(Bands, RefusesInconsistentSources) {
  const Capture c = MakeCapture();
  BandSource source;
  source.width = c.size;
  source.height = c.size;
  source.masked_pixels = c.out.mask.count() + 1;  // one the bands will not hold
  source.read = [&](int y0, int y1, bool) { return Band(c, y0, y1); };
  const auto ignore = [](int, const NormalResult&) {};
  EXPECT_THROW(EstimateNormalsInBands(source, 8, NormalOptions{}, ignore), std::invalid_argument);
  source.masked_pixels -= 1;
  EXPECT_THROW(EstimateNormalsInBands(source, 0, NormalOptions{}, ignore), std::invalid_argument);
}

}  // namespace
}  // namespace iphong::solve
