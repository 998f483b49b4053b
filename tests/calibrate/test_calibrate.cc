// Light calibration on renders with exact lights: mirror spheres (orthographic, perspective, two
// spheres with point lights), matte spheres, known normals with highlights, semi-calibrated
// intensities, and the bad captures each must report.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "calibrate/lights.h"
#include "geometry/analytic.h"
#include "geometry/primitives.h"
#include "render/renderer.h"
#include "render/shade_normal_map.h"

namespace iphong::calibrate {
namespace {

using geometry::Camera;
using reflectance::Light;
using reflectance::Lighting;
using reflectance::Material;

double AngleDeg(const Vec3d& a, const Vec3d& b) {
  return 180 / M_PI *
         std::atan2(a.normalized().cross(b.normalized()).norm(),
                    a.normalized().dot(b.normalized()));
}

// k directions on a spiral over the hemisphere, from 5° to `max_zenith_deg` off the view axis.
std::vector<Vec3d> SpiralLights(int k, double max_zenith_deg) {
  std::vector<Vec3d> lights;
  for (int j = 0; j < k; ++j) {
    const double zenith = (5 + (max_zenith_deg - 5) * j / std::max(1, k - 1)) * M_PI / 180;
    const double azimuth = j * 2.39996;  // the golden angle
    lights.emplace_back(std::sin(zenith) * std::cos(azimuth), std::sin(zenith) * std::sin(azimuth),
                        std::cos(zenith));
  }
  return lights;
}

// One light per direction with random RGB intensities in [lo, hi] (mirror tests: red only).
std::vector<Light> RandomLights(const std::vector<Vec3d>& directions, unsigned seed, double lo,
                                double hi, bool colour = true) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<Light> lights;
  for (const Vec3d& l : directions) {
    const double r = u(random);
    const Rgb e = colour ? Rgb(r, u(random), u(random)) : Rgb(r, 0.8, 0.9);
    lights.push_back(Light::Directional(l, e));
  }
  return lights;
}

// The worst relative error of estimated intensities against the lights', each scaled to a mean
// of 1 per channel (the calibrations' convention: one global scale is unobservable).
double WorstIntensityError(const std::vector<Rgb>& estimated, const std::vector<Light>& lights) {
  Rgb mean = Rgb::Zero();
  for (const Light& l : lights) mean += l.diffuse_intensity / double(lights.size());
  double worst = 0;
  for (std::size_t j = 0; j < lights.size(); ++j) {
    const Rgb expected = lights[j].diffuse_intensity.cwiseQuotient(mean);
    worst =
        std::max(worst, (estimated[j].cwiseQuotient(expected) - Rgb::Ones()).cwiseAbs().maxCoeff());
  }
  return worst;
}

Material Mirror() {
  Material m;
  m.ks = Vec3d::Constant(0.8);  // peak 0.8: not clipped, so the energy gives the intensities
  m.shininess = 500;
  return m;
}

struct Capture {
  std::vector<ImageF> images;
  Mask mask;
  std::vector<const ImageF*> pointers() const {
    std::vector<const ImageF*> p;
    for (const ImageF& i : images) p.push_back(&i);
    return p;
  }
};

// One image per light of the surface map, each shaded by the one model.
Capture ShadeEach(const geometry::SurfaceMap& surface, const Camera& camera,
                  const Material& material, const std::vector<Light>& lights) {
  Capture c;
  c.mask = surface.mask;
  for (const Light& light : lights) {
    Lighting lighting;
    lighting.lights = {light};
    c.images.push_back(render::ShadeSurfaceMap(surface, camera, material, lighting, {}));
  }
  return c;
}

std::vector<SphereGeometry> Spheres(const Mask& mask, const Intrinsics& camera = {}) {
  std::vector<std::string> warnings;
  std::vector<SphereGeometry> spheres;
  for (const SphereOutline& o : FindSpheres(mask, {}, &warnings))
    spheres.push_back(SphereFromOutline(o, camera));
  EXPECT_TRUE(warnings.empty()) << warnings[0];
  return spheres;
}

TEST(FindSpheres, FitsTheCircleOfAPixelatedDiscToATenthOfAPixel) {
  const Camera camera = Camera::Orthographic(300, 200, 3.0);  // 100 px per unit
  const geometry::SurfaceMap s = geometry::SampleSphere(camera, Vec3d(0.1234, -0.2345, 0), 0.7);
  std::vector<std::string> warnings;
  const std::vector<SphereOutline> found = FindSpheres(s.mask, {}, &warnings);
  ASSERT_EQ(found.size(), 1u);
  // Centre (0.1234 + 1.5) * 100 = 162.34, (1.0 + 0.2345) * 100 = 123.45; radius 70.
  EXPECT_NEAR(found[0].center_x_px, 162.34, 0.05);
  EXPECT_NEAR(found[0].center_y_px, 123.45, 0.05);
  EXPECT_NEAR(found[0].radius_px, 70.0, 0.05);
  EXPECT_LT(found[0].fit_rms_px, 0.35);
  EXPECT_DOUBLE_EQ(found[0].visible_fraction, 1.0);
}

TEST(FindSpheres, ReportsNoSphereNotRoundAndClipped) {
  std::vector<std::string> warnings;
  EXPECT_THROW(
      {
        try {
          FindSpheres(Mask(64, 64, false), {}, &warnings);
        } catch (const std::invalid_argument& e) {
          EXPECT_STREQ(e.what(), "no sphere: the mask has no region of radius 6.0 px or more");
          throw;
        }
      },
      std::invalid_argument);
  Mask square(100, 100, false);
  for (int r = 20; r < 80; ++r)
    for (int c = 20; c < 80; ++c) square.inside[r * 100 + c] = 1;
  try {
    FindSpheres(square, {}, &warnings);
    ADD_FAILURE() << "a square passed for a sphere";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("is not round"), std::string::npos) << e.what();
  }
  // A sphere cut by the right edge: 3/4 of its outline visible is fitted with a warning...
  const Camera camera = Camera::Orthographic(200, 200, 2.0);
  const geometry::SurfaceMap cut = geometry::SampleSphere(camera, Vec3d(0.6, 0, 0), 0.6);
  const std::vector<SphereOutline> found = FindSpheres(cut.mask, {}, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("clipped by the image edge"), std::string::npos) << warnings[0];
  EXPECT_NEAR(found[0].center_x_px, 160, 0.1);
  EXPECT_NEAR(found[0].radius_px, 60, 0.1);
  // ...but less than half is refused.
  const geometry::SurfaceMap off = geometry::SampleSphere(camera, Vec3d(1.2, 0, 0), 0.6);
  try {
    FindSpheres(off.mask, {}, &warnings);
    ADD_FAILURE() << "a sphere mostly outside the image was fitted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("% of its outline visible): too little to fit"),
              std::string::npos)
        << e.what();
  }
}

TEST(FindSpheresInImages, FindsAMatteSphereInItsPhotosToHalfAPixel) {
  const Camera camera = Camera::Orthographic(240, 200, 2.4);  // 100 px per unit
  const geometry::SurfaceMap surface = geometry::SampleSphere(camera, Vec3d(0.2, 0.1, 0), 0.75);
  Material matte;
  matte.kd = Vec3d::Constant(0.7);
  std::vector<Light> lights;
  for (const Vec3d& l : SpiralLights(8, 50)) lights.push_back(Light::Directional(l, Rgb::Ones()));
  const Capture c = ShadeEach(surface, camera, matte, lights);
  std::vector<std::string> warnings;
  const std::vector<SphereOutline> found = FindSpheresInImages(c.pointers(), {}, &warnings);
  ASSERT_EQ(found.size(), 1u);
  // Centre (0.2 + 1.2) * 100 = 140, (1.0 - 0.1) * 100 = 90; radius 75.
  EXPECT_NEAR(found[0].center_x_px, 140, 0.5);
  EXPECT_NEAR(found[0].center_y_px, 90, 0.5);
  EXPECT_NEAR(found[0].radius_px, 75, 0.5);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].find("no mask: found a sphere in the photos at ("), 0u) << warnings[0];
  // A flat grey capture holds no sphere.
  const ImageF flat(120, 100, 3, 0.4f);
  try {
    FindSpheresInImages({&flat, &flat, &flat}, {}, &warnings);
    ADD_FAILURE() << "a sphere found in flat grey";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(
        e.what(),
        "no sphere found in the photos (no circle in their mean); give --mask or --circle");
  }
}

TEST(CalibrateMirror, OrthographicDirectionsWithinATenthOfADegreeFor12To96Lights) {
  const Camera camera = Camera::Orthographic(256, 256, 2.0);
  const geometry::SurfaceMap surface = geometry::SampleSphere(camera, Vec3d::Zero(), 0.8);
  for (int k : {12, 96}) {
    const std::vector<Vec3d> truth = SpiralLights(k, 75);
    const std::vector<Light> lights = RandomLights(truth, k, 0.6, 1.0, false);
    const Capture c = ShadeEach(surface, camera, Mirror(), lights);
    const MirrorCalibration result = CalibrateMirror(c.pointers(), Spheres(c.mask), {});
    ASSERT_TRUE(result.failed.empty());
    double worst = 0;
    for (int j = 0; j < k; ++j) {
      worst = std::max(worst, AngleDeg(result.light_dir_cam[j], truth[j]));
      EXPECT_LT(result.highlights[j][0].uncertainty_deg, 0.1);
    }
    EXPECT_LT(worst, 0.1) << k << " lights";
    ASSERT_TRUE(result.intensities_measured);
    EXPECT_LT(WorstIntensityError(result.light_intensities, lights), 0.005) << k << " lights";
    EXPECT_TRUE(result.light_position_cam.empty());
  }
}

TEST(CalibrateMirror, PerspectiveDirectionsWithinATenthOfADegree) {
  render::Scene scene;
  scene.camera = Camera::Perspective(320, 320, 30, 5);
  render::SceneObject ball;
  ball.mesh = geometry::MakeSphere(1.0, 6);
  ball.material = Mirror();
  scene.objects.push_back(ball);
  const std::vector<Vec3d> truth = SpiralLights(12, 70);
  for (const Vec3d& l : truth) scene.lighting.lights.push_back(Light::Directional(l, Rgb::Ones()));
  render::RenderOptions options;
  const render::RenderOutput out = render::Render(scene, options, true);
  Capture c;
  c.images = out.per_light;
  c.mask = out.mask;
  const Intrinsics intrinsics{scene.camera.fx, scene.camera.fy, scene.camera.cx, scene.camera.cy};
  const std::vector<SphereGeometry> spheres = Spheres(c.mask, intrinsics);
  // The cone of tangent rays puts the centre 5 radii away on the axis.
  EXPECT_NEAR(spheres[0].center_cam.z(), -5.0, 0.01);
  EXPECT_NEAR(spheres[0].center_cam.head<2>().norm(), 0.0, 0.01);
  const MirrorCalibration result = CalibrateMirror(c.pointers(), spheres, {});
  ASSERT_TRUE(result.failed.empty());
  double worst = 0, worst_orthographic = 0;
  for (std::size_t j = 0; j < truth.size(); ++j)
    worst = std::max(worst, AngleDeg(result.light_dir_cam[j], truth[j]));
  EXPECT_LT(worst, 0.1);
  // The orthographic assumption on the same photos is off by degrees: intrinsics matter.
  const MirrorCalibration orthographic = CalibrateMirror(c.pointers(), Spheres(c.mask), {});
  for (std::size_t j = 0; j < truth.size(); ++j)
    worst_orthographic =
        std::max(worst_orthographic, AngleDeg(orthographic.light_dir_cam[j], truth[j]));
  EXPECT_GT(worst_orthographic, 1.0);
}

TEST(CalibrateMirror, TwoSpheresTriangulatePointLightsWithinOnePercent) {
  // 100 px per unit; two spheres of radius 0.4 at x = ±0.9, their centres at z = 0.
  const Camera camera = Camera::Orthographic(400, 200, 4.0);
  geometry::SurfaceMap a = geometry::SampleSphere(camera, Vec3d(-0.9, 0, 0), 0.4);
  const geometry::SurfaceMap b = geometry::SampleSphere(camera, Vec3d(0.9, 0, 0), 0.4);
  for (std::size_t p = 0; p < a.mask.inside.size(); ++p) {
    if (!b.mask.inside[p]) continue;
    a.mask.inside[p] = 1;
    std::copy_n(&b.normal_cam.pixels[3 * p], 3, &a.normal_cam.pixels[3 * p]);
    std::copy_n(&b.position_cam.pixels[3 * p], 3, &a.position_cam.pixels[3 * p]);
  }
  const std::vector<Vec3d> positions = {
      {1.5, 1.0, 4.0}, {-2.0, 0.5, 3.0}, {0.3, -1.5, 5.0}, {-0.5, 2.0, 2.5}, {2.5, -0.5, 3.5}};
  std::vector<Light> lights;
  for (const Vec3d& p : positions) lights.push_back(Light::Point(p, Rgb::Ones(), false));
  const Capture c = ShadeEach(a, camera, Mirror(), lights);
  const std::vector<SphereGeometry> spheres = Spheres(c.mask);
  ASSERT_EQ(spheres.size(), 2u);
  const MirrorCalibration result = CalibrateMirror(c.pointers(), spheres, {});
  ASSERT_EQ(result.light_position_cam.size(), positions.size()) << result.positions_note;
  for (std::size_t j = 0; j < positions.size(); ++j) {
    // Calibration positions are in pixels, (x_px, −y_px, z): back to scene units.
    const Vec3d& q = result.light_position_cam[j];
    const Vec3d scene_units(q.x() / 100 - 2.0, (q.y() + 100) / 100, q.z() / 100);
    EXPECT_LT((scene_units - positions[j]).norm(), 0.01 * positions[j].norm())
        << j << ": " << scene_units.transpose();
    // The direction written is the one from the midpoint of the spheres (the origin here).
    EXPECT_LT(AngleDeg(result.light_dir_cam[j], positions[j]), 0.3);
  }
}

TEST(CalibrateMirror, ReportsMissingHighlightsSameLightsAndLightsBehind) {
  const Camera camera = Camera::Orthographic(200, 200, 2.0);
  const geometry::SurfaceMap surface = geometry::SampleSphere(camera, Vec3d::Zero(), 0.8);
  const Vec3d behind = Vec3d(0.97, 0, -0.2).normalized();  // highlight at 51° from the view
  const std::vector<Light> lights = {Light::Directional({0.3, 0.2, 0.9}, Rgb::Ones()),
                                     Light::Directional({0.3, 0.2, 0.9}, Rgb::Ones()),
                                     Light::Directional(behind, Rgb::Ones()),
                                     Light::Directional({0, 0, -1}, Rgb::Ones())};
  Capture c = ShadeEach(surface, camera, Mirror(), lights);
  MirrorCalibration result = CalibrateMirror(c.pointers(), Spheres(c.mask), {});
  ASSERT_EQ(result.failed, std::vector<int>{3});
  EXPECT_NE(result.highlights[3][0].problem.find("no highlight on the sphere at (100, 100)"),
            std::string::npos)
      << result.highlights[3][0].problem;
  c.images.pop_back();
  result = CalibrateMirror(c.pointers(), Spheres(c.mask), {});
  ASSERT_TRUE(result.failed.empty());
  EXPECT_LT(AngleDeg(result.light_dir_cam[2], behind), 0.1);
  bool same = false, behind_noted = false;
  for (const CalibrationNote& n : result.warnings) {
    same |= n.image == 0 && n.other == 1 && n.text.find("the same light") == 0;
    behind_noted |= n.image == 2 && n.text.find("behind the sphere's equator") != std::string::npos;
  }
  EXPECT_TRUE(same);
  EXPECT_TRUE(behind_noted);
}

TEST(CalibrateMirror, ClippedHighlightsGiveDirectionsButNoIntensities) {
  const Camera camera = Camera::Orthographic(200, 200, 2.0);
  const geometry::SurfaceMap surface = geometry::SampleSphere(camera, Vec3d::Zero(), 0.8);
  Material bright = Mirror();
  bright.ks = Vec3d::Constant(4.0);  // peak 4: a clipped plateau, as in a real exposure
  const std::vector<Vec3d> truth = SpiralLights(12, 60);
  std::vector<Light> lights;
  for (const Vec3d& l : truth) lights.push_back(Light::Directional(l, Rgb::Ones()));
  const Capture hdr = ShadeEach(surface, camera, bright, lights);
  Capture c = hdr;
  for (ImageF& image : c.images)
    for (float& v : image.pixels) v = std::min(v, 1.0f);
  const MirrorCalibration result = CalibrateMirror(c.pointers(), Spheres(c.mask), {});
  ASSERT_TRUE(result.failed.empty());
  for (std::size_t j = 0; j < truth.size(); ++j) {
    EXPECT_GT(result.highlights[j][0].saturated_pixels, 0);
    EXPECT_LT(AngleDeg(result.light_dir_cam[j], truth[j]), 0.1);
  }
  EXPECT_FALSE(result.intensities_measured);
  EXPECT_EQ(result.light_intensities[3], Rgb::Ones());
  // The same highlights as floats up to 4, not clipped: nothing saturated, intensities measured.
  const MirrorCalibration unclipped = CalibrateMirror(hdr.pointers(), Spheres(hdr.mask), {});
  ASSERT_TRUE(unclipped.failed.empty());
  for (std::size_t j = 0; j < truth.size(); ++j) {
    EXPECT_EQ(unclipped.highlights[j][0].saturated_pixels, 0);
    EXPECT_LT(AngleDeg(unclipped.light_dir_cam[j], truth[j]), 0.1);
  }
  EXPECT_TRUE(unclipped.intensities_measured);
  EXPECT_LT(WorstIntensityError(unclipped.light_intensities, lights), 0.01);
}

// Also as a float capture ten times as bright: values up to 10 are data, not clipping
// (solve::SaturationLevel), and come back as exactly as at 1.
TEST(CalibrateFromNormals, MatteSphereDirectionsWithinATenthAndIntensitiesWithinHalfAPercent) {
  const Camera camera = Camera::Orthographic(200, 200, 2.0);
  const geometry::SurfaceMap surface = geometry::SampleSphere(camera, Vec3d::Zero(), 0.8);
  Material matte;
  matte.kd = Vec3d(0.7, 0.6, 0.5);
  const std::vector<Vec3d> truth = SpiralLights(24, 70);
  for (const double brightness : {1.0, 10.0}) {
    std::vector<Light> lights = RandomLights(truth, 7, 0.5, 1.5);
    for (Light& light : lights) light.diffuse_intensity *= brightness;
    const Capture c = ShadeEach(surface, camera, matte, lights);
    Mask on_sphere;
    const ImageF normals = SphereNormalMap(Spheres(c.mask), 200, 200, &on_sphere);
    KnownNormalOptions options;
    options.uniform_albedo = true;
    const KnownNormalCalibration result =
        CalibrateFromNormals(c.pointers(), normals, on_sphere, options);
    for (std::size_t j = 0; j < truth.size(); ++j)
      EXPECT_LT(AngleDeg(result.light_dir_cam[j], truth[j]), 0.1) << brightness << " " << j;
    EXPECT_LT(WorstIntensityError(result.light_intensities, lights), 0.005) << brightness;
  }
}

TEST(CalibrateFromNormals, TexturedShinyObjectWithPerPixelAlbedo) {
  // Known normals, an unknown albedo pattern, and Phong highlights the fit must reject.
  const Camera camera = Camera::Orthographic(160, 160, 2.0);
  geometry::SurfaceMap surface = geometry::SampleSphere(camera, Vec3d::Zero(), 0.9);
  const std::vector<Vec3d> truth = SpiralLights(20, 60);
  Capture c;
  c.mask = surface.mask;
  for (const Vec3d& l : truth) {
    Lighting lighting;
    lighting.lights = {Light::Directional(l, Rgb::Ones())};
    Material shiny;
    shiny.kd = Vec3d::Ones();
    shiny.ks = Vec3d::Constant(0.4);
    shiny.shininess = 40;
    ImageF image = render::ShadeSurfaceMap(surface, camera, shiny, lighting, {});
    Material diffuse;
    diffuse.kd = Vec3d::Ones();
    const ImageF lambert = render::ShadeSurfaceMap(surface, camera, diffuse, lighting, {});
    for (int r = 0; r < 160; ++r) {
      for (int col = 0; col < 160; ++col) {
        const double albedo = ((r / 16 + col / 16) % 2) ? 0.8 : 0.35;
        for (int k = 0; k < 3; ++k) {
          float& v = image.at(col, r)[k];
          v = float(albedo * lambert.at(col, r)[k] + (v - lambert.at(col, r)[k]));
        }
      }
    }
    c.images.push_back(image);
  }
  const KnownNormalCalibration result =
      CalibrateFromNormals(c.pointers(), surface.normal_cam, surface.mask, {});
  double worst = 0;
  for (std::size_t j = 0; j < truth.size(); ++j)
    worst = std::max(worst, AngleDeg(result.light_dir_cam[j], truth[j]));
  EXPECT_LT(worst, 0.05);  // measured 0.008°, converged in 17 rounds
  EXPECT_TRUE(result.converged);
}

TEST(EstimateIntensities, RecoversRandomIntensitiesOfALambertianSphere) {
  const Camera camera = Camera::Orthographic(120, 120, 2.0);
  const geometry::SurfaceMap surface = geometry::SampleSphere(camera, Vec3d::Zero(), 0.9);
  Material matte;
  matte.kd = Vec3d(0.8, 0.7, 0.6);
  const std::vector<Vec3d> truth = SpiralLights(16, 50);
  const std::vector<Light> lights = RandomLights(truth, 3, 0.5, 2.0);
  const Capture c = ShadeEach(surface, camera, matte, lights);
  std::vector<const float*> pointers;
  for (const ImageF& i : c.images) pointers.push_back(i.pixels.data());
  const solve::PhotometricData data = solve::GatherObservations(
      pointers, 120, 120, surface.mask, truth, std::vector<Vec3d>(truth.size(), Vec3d::Ones()));
  const IntensityEstimate e = EstimateIntensities(data, {});
  EXPECT_LT(WorstIntensityError(e.light_intensities, lights), 0.005);
  EXPECT_GT(e.eigen_gap, 10);
  // A Lambertian render: only the sphere's attached-shadow edge is left (measured 0.001).
  EXPECT_LT(e.lambert_residual, 0.005);
}

TEST(ClosestPoint, MeetsAtTheIntersectionAndRefusesDivergingRays) {
  double gap;
  const Vec3d p = ClosestPoint({0, 0, 0}, {1, 1, 0}, {2, 0, 0}, {-1, 1, 0}, &gap);
  EXPECT_NEAR((p - Vec3d(1, 1, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR(gap, 0, 1e-12);
  // Skew rays: the midpoint of the common perpendicular, the gap its length.
  const Vec3d q = ClosestPoint({-1, 0, 0}, {1, 0, 0}, {0, -1, 1}, {0, 1, 0}, &gap);
  EXPECT_NEAR((q - Vec3d(0, 0, 0.5)).norm(), 0, 1e-12);
  EXPECT_NEAR(gap, 1, 1e-12);
  ClosestPoint({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, &gap);  // parallel
  EXPECT_TRUE(std::isinf(gap));
  ClosestPoint({0, 0, 0}, {-1, -1, 0}, {2, 0, 0}, {1, -1, 0}, &gap);  // meet behind
  EXPECT_TRUE(std::isinf(gap));
}

}  // namespace
}  // namespace iphong::calibrate
