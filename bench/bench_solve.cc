// Normal recovery on 100 000 synthetic pixels × 96 lights, Woodham beside every later stage in
// the same run: the global search and local fit with known coefficients (issue 4's figure), and
// with unknown ones the model choice by held-out prediction before them (issue 12). Observations
// come from the shared model.
//   build/bench/bench_solve
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "reflectance/phong.h"
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

const solve::PhotometricData& Data() {
  static const solve::PhotometricData data = MakeData(100000, 96);
  return data;
}

void Run(benchmark::State& state, reflectance::Lobe model, bool color_residuals = true,
         bool known = true) {
  solve::NormalOptions o;
  o.model = model;
  o.color_residuals = color_residuals;
  o.material_known = known;
  o.ks = Vec3d::Constant(0.4);
  o.shininess = 20;
  o.threads = static_cast<int>(state.range(0));
  Data();  // built outside the timing
  for (auto _ : state) {
    const solve::NormalResult r = solve::EstimateNormals(Data(), o);
    benchmark::DoNotOptimize(r.normals.pixels.data());
    state.counters["woodham_ms"] = 1e3 * r.summary.init_seconds;
    state.counters["model_choice_ms"] = 1e3 * r.summary.model_seconds;
    state.counters["search_and_fit_ms"] = 1e3 * r.summary.solve_seconds;
    state.counters["iterations_per_pixel"] =
        static_cast<double>(r.summary.iterations) / Data().pixel_count();
  }
}

void BM_Woodham100k(benchmark::State& s) { Run(s, reflectance::Lobe::kLambert); }
void BM_Phong100k(benchmark::State& s) { Run(s, reflectance::Lobe::kPhong); }
// `--fast`: the normal fitted to the luminance (one residual per light instead of three).
void BM_Phong100kLuminance(benchmark::State& s) { Run(s, reflectance::Lobe::kPhong, false); }
// Unknown coefficients: the lobe and shininess chosen by held-out prediction first.
void BM_Estimated100k(benchmark::State& s) { Run(s, reflectance::Lobe::kPhong, true, false); }
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
BENCHMARK(BM_Phong100kLuminance)
    ->ArgName("threads")
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
