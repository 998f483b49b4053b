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

// The baseline: Eigen's SimplicialLDLT on the same 5-point graph Laplacian over the same mask
// (unit edge weights, one pixel pinned), assembled from triplets, as a first implementation would.
void Baseline(benchmark::State& state, const Input& in) {
  const int w = in.mask.width, h = in.mask.height;
  for (auto _ : state) {
    std::vector<int> index(in.mask.inside.size(), -1);
    int n = 0;
    for (std::size_t p = 0; p < index.size(); ++p) {
      if (in.mask.inside[p]) index[p] = n++;
    }
    std::vector<Eigen::Triplet<double>> triplets;
    Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(n), rhs = Eigen::VectorXd::Zero(n);
    auto edge = [&](int a, int b, double target) {
      triplets.emplace_back(a, b, -1.0), triplets.emplace_back(b, a, -1.0);
      diagonal[a] += 1, diagonal[b] += 1, rhs[a] -= target, rhs[b] += target;
    };
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        const std::size_t p = static_cast<std::size_t>(r) * w + c;
        if (index[p] < 0) continue;
        const float* n0 = in.normals.at(c, r);
        if (c + 1 < w && index[p + 1] >= 0) {
          const float* n1 = in.normals.at(c + 1, r);
          edge(index[p], index[p + 1], -0.5 * (n0[0] / n0[2] + n1[0] / n1[2]));
        }
        if (r + 1 < h && index[p + w] >= 0) {
          const float* n1 = in.normals.at(c, r + 1);
          edge(index[p], index[p + w], 0.5 * (n0[1] / n0[2] + n1[1] / n1[2]));
        }
      }
    }
    diagonal[0] += 1;
    for (int i = 0; i < n; ++i) triplets.emplace_back(i, i, diagonal[i]);
    Eigen::SparseMatrix<double> matrix(n, n);
    matrix.setFromTriplets(triplets.begin(), triplets.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(matrix);
    Eigen::VectorXd z = ldlt.solve(rhs);
    benchmark::DoNotOptimize(z.data());
    state.counters["memory_MB"] =
        (matrix.nonZeros() + ldlt.matrixL().nestedExpression().nonZeros()) * 12 / 1e6;
    state.counters["pixels"] = n;
  }
  state.SetLabel("eigen SimplicialLDLT (baseline)");
}

using integrate::LinearSolver;
using integrate::Method;

void BM_Dct612x512(benchmark::State& s) {
  Run(s, DiligentFull(), Method::kDct, LinearSolver::kAuto);
}
void BM_Fft612x512(benchmark::State& s) {
  Run(s, DiligentFull(), Method::kFft, LinearSolver::kAuto);
}
void BM_QuadraticMask50k(benchmark::State& s) {
  Run(s, Diligent(), Method::kQuadratic, LinearSolver::kAuto);
}
void BM_QuadraticMask50kCholesky(benchmark::State& s) {
  Run(s, Diligent(), Method::kQuadratic, LinearSolver::kCholesky);
}
void BM_BaselineMask50k(benchmark::State& s) { Baseline(s, Diligent()); }
void BM_BilateralMask50k(benchmark::State& s) {
  Run(s, Diligent(), Method::kBilateral, LinearSolver::kAuto);
}
void BM_Quadratic612x512(benchmark::State& s) {
  Run(s, DiligentFull(), Method::kQuadratic, LinearSolver::kAuto);
}
void BM_Quadratic612x512Cholesky(benchmark::State& s) {
  Run(s, DiligentFull(), Method::kQuadratic, LinearSolver::kCholesky);
}
void BM_Baseline612x512(benchmark::State& s) { Baseline(s, DiligentFull()); }
void BM_Dct2048(benchmark::State& s) { Run(s, Large(), Method::kDct, LinearSolver::kAuto); }
void BM_Quadratic2048(benchmark::State& s) {
  Run(s, Large(), Method::kQuadratic, LinearSolver::kAuto);
}
void BM_QuadraticMask2048(benchmark::State& s) {
  Run(s, LargeMask(), Method::kQuadratic, LinearSolver::kAuto);
}

BENCHMARK(BM_Dct612x512)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fft612x512)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_QuadraticMask50k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_QuadraticMask50kCholesky)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BaselineMask50k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BilateralMask50k)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Quadratic612x512)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Quadratic612x512Cholesky)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(BM_Baseline612x512)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(BM_Dct2048)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Quadratic2048)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_QuadraticMask2048)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
