// Material fitting and relighting, each beside a baseline measured in the same run:
//   fit-material on a DiLiGenT-sized capture (15 000 pixels × 96 lights, per-pixel kd, Phong
//     data with ambient) — one model, and the full choice (3 models × 2 folds) — against
//     Woodham on the same observations (the cheapest thing that reads them all);
//   relighting a 1024² capture under one light, against the renderer's per-pixel shading of the
//     same normal map (render::ShadeSurfaceMap), which evaluates the same model.
//   build/bench/bench_material
#include <benchmark/benchmark.h>

#include "bench_lights.h"

#include <cmath>

#include "geometry/analytic.h"
#include "material/fit.h"
#include "reflectance/phong.h"
#include "render/relight.h"
#include "render/shade_normal_map.h"
#include "solve/normals.h"

namespace {

using namespace iphong;

struct Capture {
  solve::PhotometricData data;
  std::vector<Vec3d> normals;
};

// Normals spread over a disc of the hemisphere (a sunflower), kd varying per pixel.
const Capture& Fifteen() {
  static const Capture c = [] {
    Capture c;
    const int pixels = 15000;
    const std::vector<Vec3d> lights = bench::SpiralLights(96);
    solve::PhotometricData& d = c.data;
    d.width = pixels;
    d.height = 1;
    d.images = 96;
    d.light_directions = lights;
    d.light_intensities.assign(96, Vec3d(1.0, 0.9, 0.8));
    reflectance::MaterialT<double> m;
    m.ks = Vec3d::Constant(0.3);
    m.shininess = 30;
    const Vec3d ambient(0.02, 0.02, 0.02);
    for (int p = 0; p < pixels; ++p) {
      d.pixels.push_back(p);
      const double a = 2.39996 * p, r = 0.8 * std::sqrt((p + 0.5) / pixels);
      const Vec3d n = Vec3d(r * std::cos(a), r * std::sin(a), 1).normalized();
      c.normals.push_back(n);
      m.kd = Vec3d::Constant(0.3 + 0.5 * ((p * 7919) % 100) / 100.0);
      for (int j = 0; j < 96; ++j) {
        const Vec3d v = ambient + reflectance::LightTerm<double>(n, Vec3d(0, 0, 1), lights[j],
                                                                 d.light_intensities[j],
                                                                 d.light_intensities[j], m, {});
        for (int k = 0; k < 3; ++k) d.values.push_back(static_cast<float>(v[k]));
      }
    }
    return c;
  }();
  return c;
}

void BM_WoodhamBaseline(benchmark::State& state) {
  const Capture& c = Fifteen();
  solve::NormalOptions o;
  o.model = reflectance::Lobe::kLambert;
  o.choose_model = false;
  o.threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(solve::RecoverNormals(c.data, o));
}
BENCHMARK(BM_WoodhamBaseline)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FitMaterial(benchmark::State& state) {
  const Capture& c = Fifteen();
  material::MaterialFitOptions o;
  if (state.range(1) == 1) o.models = {reflectance::Lobe::kPhong};
  o.threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(material::FitMaterial(c.data, c.normals, o));
}
// (threads, models): Phong alone; the full choice of three models over two folds.
BENCHMARK(BM_FitMaterial)
    ->Args({2, 1})
    ->Args({1, 3})
    ->Args({2, 3})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

struct Maps {
  geometry::Camera camera = geometry::Camera::Orthographic(1024, 1024, 2.2);
  geometry::SurfaceMap surface;
  ImageF albedo;
};

const Maps& Sphere1024() {
  static const Maps m = [] {
    Maps m;
    m.surface = geometry::SampleSphere(m.camera, Vec3d::Zero(), 1.0);
    m.albedo = ImageF(1024, 1024, 3, 0.6f);
    return m;
  }();
  return m;
}

void BM_ShadeSurfaceMapBaseline(benchmark::State& state) {
  const Maps& m = Sphere1024();
  reflectance::Material material;
  material.kd = Vec3d::Constant(0.6);
  material.ks = Vec3d::Constant(0.3);
  material.shininess = 30;
  reflectance::Lighting lighting;
  lighting.lights = {reflectance::Light::Directional(Vec3d(0.3, 0.4, 0.8), Rgb::Ones())};
  for (auto _ : state) {
    benchmark::DoNotOptimize(render::ShadeSurfaceMap(m.surface, m.camera, material, lighting, {}));
  }
}
BENCHMARK(BM_ShadeSurfaceMapBaseline)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Relight(benchmark::State& state) {
  const Maps& m = Sphere1024();
  render::RelightInput in;
  in.normals_cam = &m.surface.normal_cam;
  in.albedo = &m.albedo;
  in.lobe = reflectance::Lobe::kPhong;
  in.ks = Vec3d::Constant(0.3);
  in.shininess = 30;
  in.lights = {reflectance::Light::Directional(Vec3d(0.3, 0.4, 0.8), Rgb::Ones())};
  for (auto _ : state) benchmark::DoNotOptimize(render::Relight(in));
}
BENCHMARK(BM_Relight)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
