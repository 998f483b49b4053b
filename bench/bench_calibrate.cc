// Light calibration, each beside a baseline measured in the same run:
//   mirror sphere: 96 images of 512² with a 200 px mirror ball, against one pass that finds each
//     image's brightest pixel (what any highlight finder must at least do);
//   known normals: DiLiGenT-sized (15 000 pixels × 96 lights, uniform albedo), against Woodham
//     on the same observations;
//   semi-calibrated intensities: 100 000 pixels × 96 lights, against Woodham on them.
//   build/bench/bench_calibrate
#include <benchmark/benchmark.h>

#include "bench_lights.h"

#include <algorithm>
#include <cmath>

#include "calibrate/lights.h"
#include "geometry/analytic.h"
#include "reflectance/phong.h"
#include "render/shade_normal_map.h"
#include "solve/normals.h"

namespace {

using namespace iphong;

struct MirrorCapture {
  std::vector<ImageF> images;
  std::vector<calibrate::SphereGeometry> spheres;
};

const MirrorCapture& Mirror() {
  static const MirrorCapture capture = [] {
    MirrorCapture c;
    const geometry::Camera camera = geometry::Camera::Orthographic(512, 512, 2.56);
    const geometry::SurfaceMap s = geometry::SampleSphere(camera, Vec3d::Zero(), 1.0);
    reflectance::Material m;
    m.ks = Vec3d::Constant(0.8);
    m.shininess = 500;
    for (const Vec3d& l : bench::SpiralLights(96)) {
      reflectance::Lighting lighting;
      lighting.lights = {reflectance::Light::Directional(l, Rgb::Ones())};
      c.images.push_back(render::ShadeSurfaceMap(s, camera, m, lighting, {}));
    }
    std::vector<std::string> warnings;
    for (const auto& o : calibrate::FindSpheres(s.mask, {}, &warnings))
      c.spheres.push_back(calibrate::SphereFromOutline(o, {}));
    return c;
  }();
  return capture;
}

void BM_BrightestPixelPass(benchmark::State& state) {
  const MirrorCapture& c = Mirror();
  for (auto _ : state) {
    float sum = 0;
    for (const ImageF& image : c.images)
      sum += *std::max_element(image.pixels.begin(), image.pixels.end());
    benchmark::DoNotOptimize(sum);
  }
}
BENCHMARK(BM_BrightestPixelPass)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MirrorSphere96(benchmark::State& state) {
  const MirrorCapture& c = Mirror();
  std::vector<const ImageF*> images;
  for (const ImageF& i : c.images) images.push_back(&i);
  calibrate::MirrorOptions options;
  options.threads = static_cast<int>(state.range(0));
  for (auto _ : state)
    benchmark::DoNotOptimize(calibrate::CalibrateMirror(images, c.spheres, options));
}
BENCHMARK(BM_MirrorSphere96)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

solve::PhotometricData Observations(int pixels, const std::vector<Vec3d>& lights, bool uniform) {
  solve::PhotometricData d;
  d.width = pixels;
  d.height = 1;
  d.images = static_cast<int>(lights.size());
  d.light_directions = lights;
  d.light_intensities.assign(lights.size(), Vec3d::Ones());
  reflectance::MaterialT<double> m;
  m.ks = Vec3d::Constant(0.2);
  m.shininess = 20;
  for (int p = 0; p < pixels; ++p) {
    d.pixels.push_back(p);
    const double a = 2.39996 * p, r = 0.7 * std::sqrt((p + 0.5) / pixels);
    const Vec3d n = Vec3d(r * std::cos(a), r * std::sin(a), 1).normalized();
    m.kd = uniform ? Vec3d::Constant(0.6) : Vec3d::Constant(0.3 + 0.5 * ((p * 7919) % 100) / 100.0);
    for (std::size_t j = 0; j < lights.size(); ++j) {
      const double intensity = 0.7 + 0.6 * ((j * 37) % 96) / 96.0;
      const Vec3d c =
          reflectance::LightTerm<double>(n, Vec3d(0, 0, 1), lights[j], Vec3d::Constant(intensity),
                                         Vec3d::Constant(intensity), m, {});
      for (int k = 0; k < 3; ++k) d.values.push_back(static_cast<float>(c[k]));
    }
  }
  return d;
}

void BM_Woodham(benchmark::State& state) {
  static const solve::PhotometricData small = Observations(15000, bench::SpiralLights(96), true),
                                      large = Observations(100000, bench::SpiralLights(96), false);
  const solve::PhotometricData& d = state.range(1) == 15000 ? small : large;
  solve::NormalOptions o;
  o.model = reflectance::Lobe::kLambert;
  o.choose_model = false;
  o.threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(solve::RecoverNormals(d, o));
}
BENCHMARK(BM_Woodham)
    ->Args({2, 15000})
    ->Args({2, 100000})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_KnownNormals15k(benchmark::State& state) {
  static const std::vector<Vec3d> lights = bench::SpiralLights(96);
  static const solve::PhotometricData d = Observations(15000, lights, true);
  // As images: 15 000 × 1 pixels, one per light, and the normals they were made with.
  static const auto images = [] {
    std::vector<ImageF> out(96, ImageF(15000, 1, 3));
    for (int p = 0; p < 15000; ++p)
      for (int j = 0; j < 96; ++j)
        for (int k = 0; k < 3; ++k) out[j].pixels[3 * p + k] = d.values[(p * 96 + j) * 3 + k];
    return out;
  }();
  static const ImageF normals = [] {
    ImageF n(15000, 1, 3);
    for (int p = 0; p < 15000; ++p) {
      const double a = 2.39996 * p, r = 0.7 * std::sqrt((p + 0.5) / 15000);
      const Vec3d v = Vec3d(r * std::cos(a), r * std::sin(a), 1).normalized();
      for (int k = 0; k < 3; ++k) n.pixels[3 * p + k] = float(v[k]);
    }
    return n;
  }();
  std::vector<const ImageF*> pointers;
  for (const ImageF& i : images) pointers.push_back(&i);
  calibrate::KnownNormalOptions o;
  o.uniform_albedo = true;
  o.threads = static_cast<int>(state.range(0));
  const Mask mask(15000, 1, true);
  for (auto _ : state)
    benchmark::DoNotOptimize(calibrate::CalibrateFromNormals(pointers, normals, mask, o));
}
BENCHMARK(BM_KnownNormals15k)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_EstimateIntensities100k(benchmark::State& state) {
  static const solve::PhotometricData d = Observations(100000, bench::SpiralLights(96), false);
  calibrate::IntensityOptions o;
  o.threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(calibrate::EstimateIntensities(d, o));
}
BENCHMARK(BM_EstimateIntensities100k)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
