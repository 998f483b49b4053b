// Cost of one light term of the shared model: double (renderer) and ceres::Jet (solver), for the
// three ways of raising the lobe to the shininess. Read the figures as ratios to BM_*/Pow.
//   build/bench/bench_reflectance --benchmark_min_time=0.2
#include <benchmark/benchmark.h>
#include <ceres/jet.h>

#include <random>
#include <vector>

#include "reflectance/phong.h"

namespace {

using iphong::Vec3T;
using iphong::reflectance::Lobe;
using iphong::reflectance::MaterialT;
using iphong::reflectance::ModelOptions;
using iphong::reflectance::PowerMode;

enum Variant { kPow = 0, kIntegerSquaring = 1, kFastApprox = 2 };

struct Inputs {
  std::vector<Vec3T<double>> normals, lights;
  explicit Inputs(int count) {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-0.6, 0.6);
    for (int i = 0; i < count; ++i) {
      normals.push_back(Vec3T<double>(u(rng), u(rng), 1).normalized());
      lights.push_back(Vec3T<double>(u(rng), u(rng), 1).normalized());
    }
  }
};

template <typename T>
void Run(benchmark::State& state, const Inputs& in, Variant variant, Lobe lobe) {
  ModelOptions options;
  options.lobe = lobe;
  options.power = variant == kFastApprox ? PowerMode::kFastApprox : PowerMode::kExact;
  MaterialT<T> m;
  m.kd = Vec3T<T>(T(0.5), T(0.4), T(0.3));
  m.ks = Vec3T<T>(T(0.6), T(0.6), T(0.6));
  // 32 runs repeated squaring; 32 with a derivative part (or 32.5) forces exp(n log c).
  m.shininess = T(variant == kIntegerSquaring || variant == kFastApprox ? 32.0 : 32.5);
  const Vec3T<T> view(T(0), T(0), T(1)), intensity(T(1), T(1), T(1));
  const std::size_t count = in.normals.size();
  std::vector<Vec3T<T>> normals(count);
  for (std::size_t i = 0; i < count; ++i) {
    normals[i] = in.normals[i].template cast<T>();
    if constexpr (!std::is_floating_point_v<T>) {  // a solver's unknown normal: 3 derivatives
      for (int c = 0; c < 3; ++c) normals[i][c].v[c] = 1.0;
    }
  }
  for (auto _ : state) {
    for (std::size_t i = 0; i < count; ++i) {
      Vec3T<T> color = iphong::reflectance::LightTerm<T>(
          normals[i], view, in.lights[i].template cast<T>(), intensity, intensity, m, options);
      benchmark::DoNotOptimize(color);
    }
  }
  state.SetItemsProcessed(state.iterations() * count);
}

const Inputs& SharedInputs() {
  static const Inputs inputs(4096);
  return inputs;
}

void BM_PhongDouble(benchmark::State& s) {
  Run<double>(s, SharedInputs(), Variant(s.range(0)), Lobe::kPhong);
}
void BM_BlinnPhongDouble(benchmark::State& s) {
  Run<double>(s, SharedInputs(), Variant(s.range(0)), Lobe::kBlinnPhong);
}
void BM_PhongJet(benchmark::State& s) {
  Run<ceres::Jet<double, 5>>(s, SharedInputs(), Variant(s.range(0)), Lobe::kPhong);
}

#define IPHONG_VARIANTS ArgName("variant")->Arg(kPow)->Arg(kIntegerSquaring)->Arg(kFastApprox)
BENCHMARK(BM_PhongDouble)->IPHONG_VARIANTS;
BENCHMARK(BM_BlinnPhongDouble)->IPHONG_VARIANTS;
BENCHMARK(BM_PhongJet)->IPHONG_VARIANTS;

}  // namespace

BENCHMARK_MAIN();
