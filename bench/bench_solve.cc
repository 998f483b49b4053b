// Normal recovery on 100 000 synthetic pixels × 96 lights, Woodham beside every later stage in
// the same run: the global search and local fit with known coefficients (issue 4's figure), and
// with unknown ones the model choice by held-out prediction before them (issue 12). Observations
// come from the shared model. Then the demo's sphere (256², 32 924 pixels, red Phong) from two
// of its images, the global solver with priors, beside Woodham on all twelve.
//   build/bench/bench_solve
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "reflectance/phong.h"
#include "solve/metrics.h"
#include "solve/normals.h"

namespace {

using namespace iphong;

solve::PhotometricData MakeData(int pixels, int lights) {
  solve::PhotometricData d;
  d.width = pixels;
  d.height = 1;
  d.images = lights;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int j = 0; j < lights; ++j) {
    const double z = 1 - 0.6 * (j + 0.5) / lights, r = std::sqrt(1 - z * z);
    d.light_directions.emplace_back(r * std::cos(golden * j), r * std::sin(golden * j), z);
    d.light_intensities.push_back(Vec3d::Ones());
  }
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.7, 0.7), albedo(0.2, 0.9);
  reflectance::MaterialT<double> m;
  m.ks = Vec3d::Constant(0.4);
  m.shininess = 20;
  for (int p = 0; p < pixels; ++p) {
    d.pixels.push_back(p);
    const Vec3d n = Vec3d(u(rng), u(rng), 1).normalized();
    m.kd = Vec3d(albedo(rng), albedo(rng), albedo(rng));
    for (int j = 0; j < lights; ++j) {
      const Vec3d c = reflectance::LightTerm<double>(n, Vec3d(0, 0, 1), d.light_directions[j],
                                                     Vec3d::Ones(), Vec3d::Ones(), m, {});
      for (int k = 0; k < 3; ++k) d.values.push_back(static_cast<float>(c[k]));
    }
  }
  return d;
}

const solve::PhotometricData& Data(int lights = 96) {
  static const solve::PhotometricData data96 = MakeData(100000, 96);
  static const solve::PhotometricData data12 = MakeData(100000, 12);
  return lights == 12 ? data12 : data96;
}

void Run(benchmark::State& state, reflectance::Lobe model, bool color_residuals = true,
         bool known = true, int lights = 96) {
  solve::NormalOptions o;
  o.model = model;
  o.color_residuals = color_residuals;
  o.material_known = known;
  o.ks = Vec3d::Constant(0.4);
  o.shininess = 20;
  o.threads = static_cast<int>(state.range(0));
  const solve::PhotometricData& data = Data(lights);  // built outside the timing
  for (auto _ : state) {
    const solve::NormalResult r = solve::EstimateNormals(data, o);
    benchmark::DoNotOptimize(r.normals.pixels.data());
    state.counters["woodham_ms"] = 1e3 * r.summary.init_seconds;
    state.counters["model_choice_ms"] = 1e3 * r.summary.model_seconds;
    state.counters["search_and_fit_ms"] = 1e3 * r.summary.solve_seconds;
    state.counters["iterations_per_pixel"] =
        static_cast<double>(r.summary.iterations) / data.pixel_count();
  }
}

void BM_Woodham100k(benchmark::State& s) { Run(s, reflectance::Lobe::kLambert); }
void BM_Phong100k(benchmark::State& s) { Run(s, reflectance::Lobe::kPhong); }
// `--fast`: the normal fitted to the luminance (one residual per light instead of three).
void BM_Phong100kLuminance(benchmark::State& s) { Run(s, reflectance::Lobe::kPhong, false); }
// Unknown coefficients: the lobe and shininess chosen by held-out prediction first.
void BM_Estimated100k(benchmark::State& s) { Run(s, reflectance::Lobe::kPhong, true, false); }
// The same under 12 lights (a UW-sized rig): the held-out folds are then single lights.
void BM_Woodham100kLights12(benchmark::State& s) {
  Run(s, reflectance::Lobe::kLambert, true, true, 12);
}
void BM_Estimated100kLights12(benchmark::State& s) {
  Run(s, reflectance::Lobe::kPhong, true, false, 12);
}
BENCHMARK(BM_Woodham100k)->ArgName("threads")->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Phong100k)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_Estimated100k)
    ->ArgName("threads")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_Woodham100kLights12)
    ->ArgName("threads")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Estimated100kLights12)
    ->ArgName("threads")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_Phong100kLuminance)
    ->ArgName("threads")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

// The demo's sphere: radius 100 pixels in 256², kd (0.9, 0.2, 0.1), ks (0.5, 0.5, 0.4), n 10
// (cmd_demo.cc), under the demo's twelve lights at intensity 0.6; `lights` picks which.
struct DemoSphere {
  solve::PhotometricData data;
  ImageF normals;
  Mask mask;
};
DemoSphere MakeDemoSphere(const std::vector<int>& lights) {
  const std::vector<Vec3d> demo = {{0.22220486, 0, 0.975},
                                   {-0.280175917, 0.256664091, 0.925},
                                   {0.0423247972, -0.482269231, 0.875},
                                   {0.343848713, 0.448489758, 0.825},
                                   {-0.622300748, -0.110076241, 0.775},
                                   {0.581135503, -0.369670837, 0.725},
                                   {-0.19154066, 0.712521702, 0.675},
                                   {-0.35979543, -0.692764209, 0.625},
                                   {0.76850892, 0.280658227, 0.575},
                                   {-0.786712562, 0.324743507, 0.525},
                                   {0.372978457, -0.797033293, 0.475},
                                   {0.270909761, 0.863703017, 0.425}};
  DemoSphere s;
  const int size = 256;
  s.mask = Mask(size, size, false);
  s.normals = ImageF(size, size, 3);
  s.data.width = s.data.height = size;
  s.data.images = static_cast<int>(lights.size());
  for (int j : lights) {
    s.data.light_directions.push_back(demo[j].normalized());
    s.data.light_intensities.push_back(Vec3d::Constant(0.6));
  }
  reflectance::MaterialT<double> m;
  m.kd = Vec3d(0.9, 0.2, 0.1);
  m.ks = Vec3d(0.5, 0.5, 0.4);
  m.shininess = 10;
  for (int row = 0; row < size; ++row) {
    for (int col = 0; col < size; ++col) {
      const double x = (col + 0.5 - 128) / 100, y = -(row + 0.5 - 128) / 100;
      if (x * x + y * y >= 1) continue;
      const int p = row * size + col;
      const Vec3d n(x, y, std::sqrt(1 - x * x - y * y));
      s.mask.inside[p] = true;
      for (int c = 0; c < 3; ++c) s.normals.pixels[3 * p + c] = static_cast<float>(n[c]);
      s.data.pixels.push_back(p);
      for (int j = 0; j < s.data.images; ++j) {
        const Vec3d e = s.data.light_intensities[j];
        const Vec3d v = reflectance::LightTerm<double>(n, Vec3d(0, 0, 1),
                                                       s.data.light_directions[j], e, e, m, {});
        for (int c = 0; c < 3; ++c) s.data.values.push_back(static_cast<float>(v[c]));
      }
    }
  }
  return s;
}

void RunDemoSphere(benchmark::State& state, const std::vector<int>& lights, bool woodham) {
  const DemoSphere s = MakeDemoSphere(lights);
  solve::NormalOptions o;
  o.model = woodham ? reflectance::Lobe::kLambert : reflectance::Lobe::kPhong;
  o.material_known = !woodham;
  o.ks = Vec3d(0.5, 0.5, 0.4);
  o.shininess = 10;
  o.known_albedo = Vec3d(0.9, 0.2, 0.1);
  o.threads = 2;
  for (auto _ : state) {
    const solve::NormalResult r = solve::RecoverNormals(s.data, o);
    state.counters["mean_error_deg"] = solve::CompareNormals(r.normals, s.normals, s.mask).mean_deg;
    state.counters["iterations"] = static_cast<double>(r.summary.iterations);
  }
}
// Baseline: Woodham on all twelve images.
void BM_DemoSphereWoodham12(benchmark::State& s) {
  RunDemoSphere(s, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, true);
}
// Two images (lights 1+2, 6+7): the global solver with priors, coarse to fine.
void BM_DemoSphereTwoImages(benchmark::State& s) {
  const int first = static_cast<int>(s.range(0));
  RunDemoSphere(s, {first, first + 1}, false);
}
void BM_DemoSphereOneImage(benchmark::State& s) {
  RunDemoSphere(s, {static_cast<int>(s.range(0))}, false);
}
BENCHMARK(BM_DemoSphereWoodham12)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_DemoSphereTwoImages)
    ->ArgName("first_light")
    ->Arg(0)
    ->Arg(5)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_DemoSphereOneImage)
    ->ArgName("light")
    ->Arg(0)
    ->Arg(5)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
