// Integration speed: DCT on a full DiLiGenT-sized rectangle, the masked least-squares solve on
// a DiLiGenT-sized mask and on a 2048² image, each beside Eigen's SimplicialLDLT on the same
// system (the straightforward baseline) measured in the same run.
#include <benchmark/benchmark.h>

#include <Eigen/SparseCholesky>
#include <cmath>

#include "integrate/integrate.h"

namespace {

using namespace iphong;

// A smooth bumpy surface z(x, y) in pixel units, its normal map and an elliptic mask covering
// `fill` of the image.
struct Input {
  ImageF normals;
  Mask mask;
};

Input MakeInput(int width, int height, double fill) {
  Input in{ImageF(width, height, 3), Mask(width, height, false)};
  const double a = 0.5 * width * std::sqrt(fill), b = 0.5 * height * std::sqrt(fill);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const double x = c + 0.5 - 0.5 * width, y = 0.5 * height - r - 0.5;
      const double s = 0.05 * width;
      const double p = -0.3 * std::sin(x / s) * std::cos(y / s);
      const double q = 0.3 * std::cos(x / s) * std::sin(y / s);
      Vec3d n(-p, -q, 1);
      n.normalize();
      float* o = in.normals.at(c, r);
      o[0] = n.x(), o[1] = n.y(), o[2] = n.z();
      const bool inside = fill >= 1 || (x * x) / (a * a) + (y * y) / (b * b) <= 1;
      in.mask.inside[static_cast<std::size_t>(r) * width + c] = inside;
    }
  }
  return in;
}

void Run(benchmark::State& state, const Input& in, integrate::Method method,
         integrate::LinearSolver solver) {
  integrate::IntegrateOptions options;
  options.method = method;
  options.solver = solver;
  integrate::IntegrateSummary summary;
  for (auto _ : state) {
    auto result = integrate::IntegrateNormals(in.normals, in.mask, options);
    benchmark::DoNotOptimize(result.height.pixels.data());
    summary = result.summary;
  }
  state.counters["pixels"] = static_cast<double>(summary.pixels);
  state.counters["memory_MB"] = summary.memory_bytes / 1e6;
  state.counters["setup_ms"] = summary.setup_seconds * 1e3;
  state.counters["solve_ms"] = summary.solve_seconds * 1e3;
  state.counters["cg_iterations"] = static_cast<double>(summary.iterations);
  state.SetLabel(summary.solver);
}

const Input& Diligent() {
  static const Input in = MakeInput(612, 512, 0.2);  // ≈ 50k pixels, like ball or cat
  return in;
}
const Input& DiligentFull() {
  static const Input in = MakeInput(612, 512, 1.0);
  return in;
}
const Input& Large() {
  static const Input in = MakeInput(2048, 2048, 1.0);
  return in;
}
const Input& LargeMask() {
  static const Input in = MakeInput(2048, 2048, 0.6);
  return in;
}

void BM_Dct612x512(benchmark::State& s) {
  Run(s, DiligentFull(), integrate::Method::kDct, integrate::LinearSolver::kAuto);
}
void BM_Fft612x512(benchmark::State& s) {
  Run(s, DiligentFull(), integrate::Method::kFft, integrate::LinearSolver::kAuto);
}
void BM_QuadraticMask50k(benchmark::State& s) {
  Run(s, Diligent(), integrate::Method::kQuadratic, integrate::LinearSolver::kAuto);
}
void BM_QuadraticMask50kCg(benchmark::State& s) {
  Run(s, Diligent(), integrate::Method::kQuadratic, integrate::LinearSolver::kConjugateGradient);
}
void BM_Dct2048(benchmark::State& s) {
  Run(s, Large(), integrate::Method::kDct, integrate::LinearSolver::kAuto);
}
void BM_Quadratic2048(benchmark::State& s) {
  Run(s, Large(), integrate::Method::kQuadratic, integrate::LinearSolver::kAuto);
}
void BM_Quadratic2048Cg(benchmark::State& s) {
  Run(s, Large(), integrate::Method::kQuadratic, integrate::LinearSolver::kConjugateGradient);
}
void BM_QuadraticMask2048(benchmark::State& s) {
  Run(s, LargeMask(), integrate::Method::kQuadratic, integrate::LinearSolver::kAuto);
}
void BM_BilateralMask50k(benchmark::State& s) {
  Run(s, Diligent(), integrate::Method::kBilateral, integrate::LinearSolver::kAuto);
}

BENCHMARK(BM_Dct612x512)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fft612x512)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_QuadraticMask50k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_QuadraticMask50kCg)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BilateralMask50k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Dct2048)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Quadratic2048)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Quadratic2048Cg)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_QuadraticMask2048)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
