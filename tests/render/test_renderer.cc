// The renderer against analytic shading: convergence, seed 001's Gouraud/Phong claim, shadows.
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/analytic.h"
#include "geometry/primitives.h"
#include "render/preview.h"
#include "render/renderer.h"
#include "render/shade_normal_map.h"

namespace iphong::render {
namespace {

using reflectance::Light;

Scene SphereScene(int subdivisions, int size) {
  Scene scene;
  scene.camera = geometry::Camera::Orthographic(size, size, 2.0);
  scene.lighting.ambient = Vec3d(1, 1, 1);
  scene.lighting.lights = {Light::Directional(Vec3d(0.3, 0.4, 0.866), Vec3d::Ones())};
  SceneObject sphere;
  sphere.mesh = geometry::MakeSphere(0.8, subdivisions);
  sphere.material.ka = Vec3d(0.1, 0.1, 0.1);
  sphere.material.kd = Vec3d(0.9, 0.2, 0.1);
  sphere.material.ks = Vec3d(0.5, 0.5, 0.4);
  sphere.material.shininess = 10;
  scene.objects.push_back(sphere);
  return scene;
}

// A ball of radius 0.3 floating 0.6 above a floor plane (z = 0) at x = 0.3, both of `material`,
// under an orthographic camera of size² pixels; no lights.
Scene BallOnFloorScene(int size, const reflectance::Material& material) {
  Scene scene;
  scene.camera = geometry::Camera::Orthographic(size, size, 2.0);
  SceneObject floor, ball;
  floor.mesh = geometry::MakePlane(1.9, 4);
  floor.material = material;
  ball.mesh = geometry::MakeSphere(0.3, 4);
  Eigen::Affine3d up = Eigen::Affine3d::Identity();
  up.translate(Vec3d(0.3, 0, 0.6));
  geometry::TransformMesh(ball.mesh, up);
  ball.material = material;
  scene.objects = {floor, ball};
  return scene;
}

// Mean |rendered − analytic| over pixels both see, in [0, 1] image units.
double MeanErrorAgainstAnalytic(const Scene& scene, const RenderOptions& options) {
  const RenderOutput out = Render(scene, options, false);
  const auto analytic = geometry::SampleSphere(scene.camera, Vec3d::Zero(), 0.8);
  const ImageF exact = ShadeSurfaceMap(analytic, scene.camera, scene.objects[0].material,
                                       scene.lighting, options.model);
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t p = 0; p < out.mask.inside.size(); ++p) {
    if (!out.mask.inside[p] || !analytic.mask.inside[p]) continue;
    for (int c = 0; c < 3; ++c)
      sum += std::abs(out.image.pixels[3 * p + c] - exact.pixels[3 * p + c]);
    n += 3;
  }
  return sum / n;
}

TEST(Renderer, TessellatedSphereConvergesToAnalyticShading) {
  double previous = 1;
  for (int s = 2; s <= 6; ++s) {
    const double error = MeanErrorAgainstAnalytic(SphereScene(s, 256), RenderOptions{});
    RecordProperty("mean_abs_error_subdiv_" + std::to_string(s), std::to_string(error));
    EXPECT_LT(error, previous) << "subdivisions " << s;
    previous = error;
  }
  EXPECT_LT(previous, 2e-3);  // issue 3's bound at 6 subdivisions
}

TEST(Renderer, RenormalizingInterpolatedNormalsMattersOnCoarseMeshes) {
  // Seed 001: unnormalized interpolated normals are acceptable only for small polygons.
  RenderOptions raw;
  raw.renormalize_normals = false;
  const double with = MeanErrorAgainstAnalytic(SphereScene(2, 256), RenderOptions{});
  const double without = MeanErrorAgainstAnalytic(SphereScene(2, 256), raw);
  EXPECT_GT(without, 2 * with);
}

TEST(Renderer, PhongCatchesAHighlightInsideALargeTriangleThatGouraudMisses) {
  // One big triangle whose vertex normals splay outward, lit so the mirror direction meets the
  // viewer in the middle of the triangle: Gouraud only sees the dim vertex intensities.
  Scene scene;
  scene.camera = geometry::Camera::Orthographic(128, 128, 2.0);
  scene.lighting.lights = {Light::Directional(Vec3d(0, 0, 1), Vec3d::Ones())};
  SceneObject tri;
  tri.mesh.positions = {Vec3d(-0.9, -0.8, 0), Vec3d(0.9, -0.8, 0), Vec3d(0, 0.9, 0)};
  tri.mesh.triangles = {{0, 1, 2}};
  for (const Vec3d& p : tri.mesh.positions) {
    tri.mesh.corner_normals.push_back(Vec3d(p.x(), p.y(), 1.2).normalized());
  }
  tri.material.kd = Vec3d::Constant(0.2);
  tri.material.ks = Vec3d::Constant(0.8);
  tri.material.shininess = 50;
  scene.objects.push_back(tri);
  RenderOptions phong, gouraud;
  gouraud.shading = Shading::kGouraud;
  auto peak = [&](const RenderOptions& o) {
    const RenderOutput out = Render(scene, o, false);
    float best = 0;
    for (std::size_t p = 0; p < out.mask.inside.size(); ++p)
      if (out.mask.inside[p]) best = std::max(best, out.image.pixels[3 * p]);
    return best;
  };
  const float phong_peak = peak(phong), gouraud_peak = peak(gouraud);
  // Where the interpolated normal passes through (0, 0, 1): kd + ks = 1.
  EXPECT_GT(phong_peak, 0.97f);
  EXPECT_LT(gouraud_peak, 0.35f);
  RecordProperty("phong_peak", std::to_string(phong_peak));
  RecordProperty("gouraud_peak", std::to_string(gouraud_peak));
}

TEST(Renderer, FlatShadingIsConstantPerTriangle) {
  Scene scene = SphereScene(1, 96);
  RenderOptions flat;
  flat.shading = Shading::kFlat;
  const RenderOutput out = Render(scene, flat, false);
  // Count distinct colours: at most one per visible triangle (80 triangles at level 1).
  std::vector<float> seen;
  for (std::size_t p = 0; p < out.mask.inside.size(); ++p) {
    if (!out.mask.inside[p]) continue;
    const float v = out.image.pixels[3 * p];
    if (std::none_of(seen.begin(), seen.end(), [&](float s) { return std::abs(s - v) < 1e-6f; }))
      seen.push_back(v);
  }
  EXPECT_LE(seen.size(), 80u);
  EXPECT_GE(seen.size(), 20u);
}

TEST(Renderer, PerLightImagesSumToTheCombinedImage) {
  Scene scene = SphereScene(4, 64);
  scene.lighting.lights.push_back(Light::Directional(Vec3d(-0.5, 0.1, 0.8), Vec3d(0.5, 0.7, 0.9)));
  scene.lighting.lights.push_back(Light::Point(Vec3d(0, 2, 2), Vec3d(4, 4, 4), true));
  const RenderOutput out = Render(scene, RenderOptions{}, true);
  ASSERT_EQ(out.per_light.size(), 3u);
  const Vec3d ambient = scene.objects[0].material.ka;  // Ia = 1
  for (std::size_t p = 0; p < out.mask.inside.size(); p += 7) {
    if (!out.mask.inside[p]) continue;
    for (int c = 0; c < 3; ++c) {
      double sum = 0;
      for (const ImageF& img : out.per_light) sum += img.pixels[3 * p + c] - ambient[c];
      EXPECT_NEAR(out.image.pixels[3 * p + c], ambient[c] + sum, 1e-5);
    }
  }
}

// A per-light image is evaluated with its light alone: it must equal, bit for bit, a render of
// the scene lit by that light only — each light's own shadow map, fall-off and LED factor — in
// every shading mode. Lights of every kind, shadows cast on a floor, so a light paired with
// another's shadow map or left out would show.
TEST(Renderer, EachPerLightImageIsARenderOfItsLightAlone) {
  reflectance::Material glossy;
  glossy.ka = Vec3d::Constant(0.1);
  glossy.kd = Vec3d(0.8, 0.7, 0.6);
  glossy.ks = Vec3d::Constant(0.2);
  glossy.shininess = 7.5;
  Scene scene = BallOnFloorScene(64, glossy);
  scene.lighting.ambient = Vec3d(0.5, 0.6, 0.7);
  scene.lighting.lights = {
      Light::Directional(Vec3d(-0.6, 0, 0.8), Vec3d(1, 0.9, 0.8)),
      Light::Point(Vec3d(-1, 1, 3), Vec3d(9, 9, 9), true),
      Light::Led(Vec3d(1.5, -1, 2.5), Vec3d(8, 7, 6), Vec3d(-1.5, 1, -2.5), 1.7),
      Light::Directional(Vec3d(0.2, 0.7, 0.7), Vec3d(0.4, 0.5, 0.6))};
  for (const Shading shading : {Shading::kPhong, Shading::kGouraud, Shading::kFlat}) {
    RenderOptions options;
    options.shading = shading;
    options.shadows = true;
    options.shadow_map_size = 256;
    const RenderOutput all = Render(scene, options, true);
    ASSERT_EQ(all.per_light.size(), scene.lighting.lights.size());
    for (std::size_t j = 0; j < scene.lighting.lights.size(); ++j) {
      Scene alone = scene;
      alone.lighting.lights = {scene.lighting.lights[j]};
      const RenderOutput one = Render(alone, options, false);
      std::size_t differ = 0, lit = 0;
      for (std::size_t i = 0; i < one.image.pixels.size(); ++i) {
        differ += all.per_light[j].pixels[i] != one.image.pixels[i];
        lit += one.image.pixels[i] > 0.2f;
      }
      EXPECT_EQ(differ, 0u) << ShadingName(shading) << ", light " << j;
      EXPECT_GT(lit, 300u) << ShadingName(shading) << ", light " << j;
    }
  }
}

TEST(Renderer, GroundTruthNormalsAreExactOnAPlane) {
  Scene scene;
  scene.camera = geometry::Camera::Orthographic(32, 32, 2.0);
  scene.lighting.lights = {Light::Directional(Vec3d(0, 0, 1), Vec3d::Ones())};
  SceneObject plane;
  plane.mesh = geometry::MakePlane(1.0, 3);
  Eigen::Affine3d tilt = Eigen::Affine3d::Identity();
  tilt.rotate(Eigen::AngleAxisd(0.3, Vec3d::UnitY()));
  geometry::TransformMesh(plane.mesh, tilt);
  plane.material.kd = Vec3d(0.25, 0.5, 0.75);
  scene.objects.push_back(plane);
  const RenderOutput out = Render(scene, RenderOptions{}, false);
  const Vec3d expected = tilt.linear() * Vec3d(0, 0, 1);
  std::size_t inside = 0;
  for (std::size_t p = 0; p < out.mask.inside.size(); ++p) {
    if (!out.mask.inside[p]) {
      EXPECT_EQ(out.normal_cam.pixels[3 * p + 2], 0.0f);
      continue;
    }
    ++inside;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(out.normal_cam.pixels[3 * p + c], expected[c], 1e-6);
      EXPECT_NEAR(out.albedo.pixels[3 * p + c], plane.material.kd[c], 1e-7);
      EXPECT_NEAR(out.image.pixels[3 * p + c], plane.material.kd[c] * expected.z(), 1e-6);
    }
  }
  EXPECT_GT(inside, 100u);
}

TEST(Renderer, ShadowMapsDarkenThePlaneUnderASphere) {
  reflectance::Material matte;
  matte.ka = Vec3d::Constant(0.1);
  matte.kd = Vec3d::Constant(0.8);
  Scene scene = BallOnFloorScene(96, matte);
  scene.lighting.ambient = Vec3d::Constant(1);
  // Light from the upper left: the ball's shadow falls down and to the right of it on the floor.
  scene.lighting.lights = {Light::Directional(Vec3d(-0.6, 0, 0.8), Vec3d::Ones())};
  RenderOptions lit, shadowed;
  shadowed.shadows = true;
  shadowed.shadow_map_size = 1024;
  const RenderOutput a = Render(scene, lit, false), b = Render(scene, shadowed, false);
  // Floor point straight "behind" the ball centre along −L: (0.3, 0, 0.6) − 0.75·(−0.6, 0, 0.8).
  const auto pixel = [&](double x, double y) {
    const int col = static_cast<int>((x + 1) / 2 * 96), row = static_cast<int>((1 - y) / 2 * 96);
    return 3 * (static_cast<std::size_t>(row) * 96 + col);
  };
  const std::size_t in_shadow = pixel(0.75, 0.0), far_away = pixel(-0.8, 0.8);
  EXPECT_NEAR(a.image.pixels[in_shadow], 0.1 + 0.8 * 0.8, 1e-5);  // no shadows: lit floor
  EXPECT_NEAR(b.image.pixels[in_shadow], 0.1, 1e-5);              // shadowed: ambient only
  EXPECT_NEAR(b.image.pixels[far_away], a.image.pixels[far_away], 1e-6);
  // No self-shadowing acne on the directly lit floor.
  std::size_t acne = 0;
  for (std::size_t p = 0; p < a.mask.inside.size(); ++p) {
    if (a.mask.inside[p] && std::abs(a.depth.pixels[p]) < 1e-6 &&  // floor at z = 0
        std::hypot(((p % 96) + 0.5) / 48 - 1 - 0.75, 1 - ((p / 96) + 0.5) / 48) > 0.45 &&
        b.image.pixels[3 * p] < a.image.pixels[3 * p] - 1e-4) {
      ++acne;
    }
  }
  EXPECT_EQ(acne, 0u);
}

TEST(Renderer, SupersamplingAntiAliasesEdgesButKeepsTheInterior) {
  Scene scene = SphereScene(5, 64);
  RenderOptions ss;
  ss.supersampling = 4;
  const RenderOutput a = Render(scene, RenderOptions{}, false), b = Render(scene, ss, false);
  std::size_t partial = 0;
  for (std::size_t p = 0; p < a.mask.inside.size(); ++p) {
    const float v = b.image.pixels[3 * p];
    if (!b.mask.inside[p] && v > 0.01f) ++partial;  // edge pixels blend with the background
  }
  EXPECT_GT(partial, 20u);
  const std::size_t centre = 3 * (32 * 64 + 32);
  EXPECT_NEAR(b.image.pixels[centre], a.image.pixels[centre], 0.02);
  const float* n = b.normal_cam.pixels.data() + centre;
  EXPECT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-5);
}

TEST(Renderer, GaussianNoiseHasTheRequestedSigmaAndIsSeeded) {
  ImageF base(200, 200, 1, 0.5f);
  NoiseOptions noise;
  noise.gaussian_sigma = 0.02;
  noise.seed = 7;
  ImageF a = base, b = base, c = base;
  ApplyNoise(a, noise, 0);
  ApplyNoise(b, noise, 0);
  ApplyNoise(c, noise, 1);
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_NE(a.pixels, c.pixels);
  double sum2 = 0;
  for (float v : a.pixels) sum2 += (v - 0.5) * (v - 0.5);
  EXPECT_NEAR(std::sqrt(sum2 / a.pixels.size()), 0.02, 0.001);
  NoiseOptions q;
  q.quantization_bits = 8;
  ImageF d(1, 1, 1, 0.3f);
  ApplyNoise(d, q, 0);
  EXPECT_FLOAT_EQ(d.pixels[0], std::round(0.3 * 255) / 255);
}

TEST(Renderer, InvalidScenesAndOptionsAreRejected) {
  Scene empty;
  EXPECT_THROW(Render(empty, RenderOptions{}, false), std::invalid_argument);
  Scene scene = SphereScene(1, 16);
  RenderOptions bad;
  bad.supersampling = 0;
  EXPECT_THROW(Render(scene, bad, false), std::invalid_argument);
  scene.objects[0].material.ks[0] = -1;
  try {
    Render(scene, RenderOptions{}, false);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("object 0"), std::string::npos) << e.what();
  }
}

TEST(Preview, LeavesOutSilhouetteWallsOnly) {
  // A 4x4 flat square at height 0 and a wall rising from its top edge straight toward the viewer:
  // the wall's normal is perpendicular to the view axis.
  geometry::TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {4, 4, 6}, {0, 4, 6}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {3, 2, 4}, {3, 4, 5}};
  geometry::ComputeFlatNormals(mesh);
  auto picture = [](const geometry::TriangleMesh& m, double max_wall_deg) {
    PreviewOptions options;
    options.width = 64;
    options.max_wall_deg = max_wall_deg;
    return RenderPreview(m, options).pixels;
  };
  // The floor alone, framed the same (same vertices), is exactly what 80° leaves.
  geometry::TriangleMesh floor = mesh;
  floor.triangles.resize(2);
  geometry::ComputeFlatNormals(floor);
  EXPECT_EQ(picture(mesh, 80), picture(floor, 90));
  EXPECT_NE(picture(mesh, 90), picture(floor, 90));  // 90° keeps the wall
}

TEST(Preview, ShadowsKeepTheSurfacesColour) {
  // A square of pure red albedo: outside the (white) specular highlight the picture holds no
  // green or blue, in lit and in unlit parts alike.
  geometry::TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  geometry::ComputeFlatNormals(mesh);
  ImageF red(4, 4, 3, 0.0f);
  for (std::size_t p = 0; p < red.pixel_count(); ++p) red.pixels[3 * p] = 0.5f;
  PreviewOptions options;
  options.width = 64;
  options.texture = &red;
  const ImageF picture = RenderPreview(mesh, options);
  std::vector<double> green_over_red;
  for (std::size_t p = 0; p < picture.pixel_count(); ++p) {
    const float* v = picture.pixels.data() + 3 * p;
    if (v[0] == v[1] && v[1] == v[2]) continue;  // the grey background
    green_over_red.push_back(v[1] / v[0]);
  }
  ASSERT_GT(green_over_red.size(), 100u);
  std::nth_element(green_over_red.begin(), green_over_red.begin() + green_over_red.size() / 2,
                   green_over_red.end());
  EXPECT_LT(green_over_red[green_over_red.size() / 2], 0.02);
}

}  // namespace
}  // namespace iphong::render
