// Issue 3's target: a 1024×1024 Phong-shaded render of a ≥200k-triangle mesh with 4 lights,
// reported as pixels per second per core (items_per_second / threads). Beside it, the same
// normals shaded by the array API (no rasterization) as the baseline measured in this run.
//   build/bench/bench_render --benchmark_min_time=1
#include <benchmark/benchmark.h>

#include <cmath>

#include "geometry/primitives.h"
#include "reflectance/shade.h"
#include "render/renderer.h"

namespace {

using namespace iphong;

render::Scene BenchScene() {
  render::Scene scene;
  scene.camera = geometry::Camera::Orthographic(1024, 1024, 2.0);
  scene.lighting.ambient = Vec3d::Constant(0.2);
  for (const Vec3d& d : {Vec3d(0.3, 0.4, 0.866), Vec3d(-0.5, 0.2, 0.8), Vec3d(0.1, -0.6, 0.7),
                         Vec3d(-0.2, -0.1, 1.0)}) {
    scene.lighting.lights.push_back(reflectance::Light::Directional(d, Vec3d::Constant(0.5)));
  }
  render::SceneObject torus;
  torus.mesh = geometry::MakeTorus(0.6, 0.3, 512, 256);  // 262 144 triangles
  torus.material = reflectance::FindMaterialPreset("jade").material;
  scene.objects.push_back(torus);
  return scene;
}

const render::Scene& SharedScene() {
  static const render::Scene scene = BenchScene();
  return scene;
}

void BM_RenderPhong1024(benchmark::State& state) {
  const render::Scene& scene = SharedScene();
  render::RenderOptions options;
  options.threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    render::RenderOutput out = render::Render(scene, options, false);
    benchmark::DoNotOptimize(out.image.pixels.data());
    state.counters["raster_ms"] = out.raster_seconds * 1e3;
    state.counters["shade_ms"] = out.shade_seconds * 1e3;
  }
  state.counters["triangles"] = static_cast<double>(scene.objects[0].mesh.triangle_count());
  state.counters["Mpix_per_s_per_core"] = benchmark::Counter(
      1024.0 * 1024.0 / 1e6 / options.threads, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_RenderPhong1024)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// A photometric dataset: one image per light (render --per-light), 48 LEDs (anisotropy 1.5) over
// a 512² glossy sphere, 1 thread; reported as image pixels per second (49 images of 512²).
// Baseline in the same run: the combined image alone, whose every pixel evaluates all 48 lights.
void RenderLeds(benchmark::State& state, bool per_light) {
  render::Scene scene;
  scene.camera = geometry::Camera::Orthographic(512, 512, 2.0);
  scene.lighting.ambient = Vec3d::Constant(0.05);
  for (int j = 0; j < 48; ++j) {
    const double azimuth = 2.399963 * j, elevation = 0.35 + 0.9 * (j + 0.5) / 48;
    const Vec3d position =
        3.0 * Vec3d(std::cos(elevation) * std::cos(azimuth),
                    std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    scene.lighting.lights.push_back(
        reflectance::Light::Led(position, Vec3d::Constant(9.0), -position, 1.5));
  }
  render::SceneObject sphere;
  sphere.mesh = geometry::MakeSphere(0.9, 6);
  sphere.material = reflectance::FindMaterialPreset("jade").material;
  scene.objects.push_back(sphere);
  render::RenderOptions options;
  options.threads = 1;
  for (auto _ : state) {
    render::RenderOutput out = render::Render(scene, options, per_light);
    benchmark::DoNotOptimize(out.image.pixels.data());
  }
  const double images = per_light ? scene.lighting.lights.size() + 1.0 : 1.0;
  state.counters["Mpix_images_per_s"] = benchmark::Counter(
      512.0 * 512.0 * images / 1e6, benchmark::Counter::kIsIterationInvariantRate);
}
void BM_RenderPerLight48Leds(benchmark::State& state) { RenderLeds(state, true); }
void BM_RenderCombined48Leds(benchmark::State& state) { RenderLeds(state, false); }
BENCHMARK(BM_RenderPerLight48Leds)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderCombined48Leds)->Unit(benchmark::kMillisecond)->UseRealTime();

// Baseline: the model alone over the same 1024² normal map (what a per-pixel evaluation costs).
void BM_ShadeNormalMap1024(benchmark::State& state) {
  const render::Scene& scene = SharedScene();
  render::RenderOptions options;
  const render::RenderOutput out = render::Render(scene, options, false);
  std::vector<float> colors(out.normal_cam.pixels.size());
  const float view[3] = {0, 0, 1};
  reflectance::PointsView<float> points;
  points.normals_cam = out.normal_cam.pixels.data();
  points.count = out.normal_cam.pixel_count();
  points.views_cam = view;
  points.mask = out.mask.inside.data();
  for (auto _ : state) {
    reflectance::ShadePoints(points, scene.objects[0].material, scene.lighting, options.model,
                             colors.data(), 1);
    benchmark::DoNotOptimize(colors.data());
  }
  state.counters["Mpix_per_s_per_core"] =
      benchmark::Counter(1024.0 * 1024.0 / 1e6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ShadeNormalMap1024)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
