// The masked least-squares problem: a weighted graph Laplacian over the pixels of the mask.
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#ifdef IPHONG_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "integrate/internal.h"
#include "integrate/multigrid.h"

namespace iphong::integrate::internal {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

double Sigmoid(double x) { return 1 / (1 + std::exp(-x)); }
double Square(double x) { return x * x; }

// The mask's pixels and their right / lower neighbours, in mask (row-major) order.
struct Grid {
  int width = 0, height = 0;
  std::vector<int> pixel;  // mask index → grid index
  std::vector<int> right;  // mask index of the right neighbour, or −1
  std::vector<int> down;   // mask index of the neighbour below, or −1
  std::vector<int> left, up;
  std::vector<int> col, row;  // pixel of each mask index

  explicit Grid(const Mask& mask) : width(mask.width), height(mask.height) {
    std::vector<int> index(mask.inside.size(), -1);
    for (std::size_t p = 0; p < mask.inside.size(); ++p) {
      if (mask.inside[p]) {
        index[p] = static_cast<int>(pixel.size());
        pixel.push_back(static_cast<int>(p));
        col.push_back(static_cast<int>(p % width));
        row.push_back(static_cast<int>(p / width));
      }
    }
    const std::size_t n = pixel.size();
    right.assign(n, -1), down.assign(n, -1), left.assign(n, -1), up.assign(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
      const int p = pixel[i], c = p % width, r = p / width;
      if (c + 1 < width && index[p + 1] >= 0) {
        right[i] = index[p + 1];
        left[index[p + 1]] = static_cast<int>(i);
      }
      if (r + 1 < height && index[p + width] >= 0) {
        down[i] = index[p + width];
        up[index[p + width]] = static_cast<int>(i);
      }
    }
  }
  std::size_t size() const { return pixel.size(); }
};

// One edge equation per neighbour pair: f[b] − f[a] = target, with a weight.
struct Edges {
  std::vector<double> weight_right, target_right, weight_down, target_down;  // per mask index
};

// Weights of the one-sided equations per pixel and direction: forward (to the right / below)
// and backward. The quadratic problem has 1/2 everywhere; the bilateral one reweights them.
struct OneSided {
  std::vector<double> forward_col, backward_col, forward_row, backward_row;
};

// A cut edge keeps this much weight, so no pixel is ever left without equations (its neighbours
// carry it along instead of leaving its height undetermined).
constexpr double kMinSum = 1e-4;

// The forward equation of a and the backward one of its neighbour b (both say f_b − f_a = their
// slope) merge into one edge equation: weight = their sum (times the view cosine), target = their
// weighted mean slope.
void MergeOneSided(double ua, double ub, double slope_a, double slope_b, double cos_edge,
                   double* weight, double* target) {
  *weight = cos_edge * std::max(ua + ub, kMinSum);
  *target = ua + ub > 0 ? (ua * slope_a + ub * slope_b) / (ua + ub) : 0.5 * (slope_a + slope_b);
}

// Creases are not depth steps. A continuous surface rises between two pixel centres by the
// integral of its slope, which lies between the two pixels' slopes however sharply it folds in
// between; a step leaves that interval. So an edge whose rise f_b − f_a lies inside it keeps the
// quadratic weights (its target the mean slope): the sigmoids alone would cut it, since at a
// crease both one-sided equations disagree with the surface as at a step, and a fold cut from rim
// to rim lets the part beyond drift on the cut edges' residual weight (a tear).
// Except at an occluding contour, where a step hides behind a rise the surface's continuity has
// smeared, so the sigmoids decide. Near a contour a smooth surface's height goes like the square
// root of the distance to it, so the cosine to the view falls by √2 or more over the last pixel
// (√(d / (d + 1)) for a pixel d < 1 from it): a side that descends toward the edge with its
// cosine that far below one of its other neighbours' (the outline need not run across the edge),
// or clamped at `min_cos`, is taken for one. A fold's walls keep their cosine.
// `slope` is d_col for an edge to the right, d_row for one below.
bool JoinedCrease(const Grid& grid, const GridGradients& g, const std::vector<float>& slope, int a,
                  int b, double rise, double min_cos, double toward_viewer) {
  const double s_a = slope[grid.pixel[a]], s_b = slope[grid.pixel[b]];
  if (rise < std::min(s_a, s_b) || rise > std::max(s_a, s_b)) return false;
  auto contour = [&](int pixel, int partner, double descent) {
    if (descent >= 0) return false;  // does not fall away toward the edge
    const double c = g.cos_view[grid.pixel[pixel]];
    if (c <= min_cos * (1 + 1e-6)) return true;
    for (int other : {grid.left[pixel], grid.right[pixel], grid.up[pixel], grid.down[pixel]}) {
      if (other >= 0 && other != partner && c * std::sqrt(2.0) <= g.cos_view[grid.pixel[other]]) {
        return true;
      }
    }
    return false;
  };
  return !contour(a, b, toward_viewer * s_a) && !contour(b, a, -toward_viewer * s_b);
}

Edges BuildEdges(const Grid& grid, const GridGradients& g, const OneSided& u) {
  const std::size_t n = grid.size();
  Edges e;
  e.weight_right.assign(n, 0), e.target_right.assign(n, 0);
  e.weight_down.assign(n, 0), e.target_down.assign(n, 0);
  for (std::size_t a = 0; a < n; ++a) {
    const int pa = grid.pixel[a];
    if (const int b = grid.right[a]; b >= 0) {
      const int pb = grid.pixel[b];
      MergeOneSided(u.forward_col[a], u.backward_col[b], g.d_col[pa], g.d_col[pb],
                    std::min(g.cos_view[pa], g.cos_view[pb]), &e.weight_right[a],
                    &e.target_right[a]);
    }
    if (const int b = grid.down[a]; b >= 0) {
      const int pb = grid.pixel[b];
      MergeOneSided(u.forward_row[a], u.backward_row[b], g.d_row[pa], g.d_row[pb],
                    std::min(g.cos_view[pa], g.cos_view[pb]), &e.weight_down[a], &e.target_down[a]);
    }
  }
  return e;
}

// Connected parts (union-find over the edges `joined` accepts); returns the part of each pixel.
template <typename Joined>
std::vector<int> Components(const Grid& grid, int* count, const Joined& joined) {
  std::vector<int> parent(grid.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t a = 0; a < grid.size(); ++a) {
    for (const int axis : {0, 1}) {
      const int b = axis == 0 ? grid.right[a] : grid.down[a];
      if (b >= 0 && joined(a, axis)) parent[find(static_cast<int>(a))] = find(b);
    }
  }
  std::vector<int> label(grid.size(), -1), root_label(grid.size(), -1);
  *count = 0;
  for (std::size_t a = 0; a < grid.size(); ++a) {
    const int root = find(static_cast<int>(a));
    if (root_label[root] < 0) root_label[root] = (*count)++;
    label[a] = root_label[root];
  }
  return label;
}

// L f = rhs with L = Σ w (e_b − e_a)(e_b − e_a)ᵀ + diag(anchor), written straight into
// compressed storage: symmetric, so the row-major and column-major arrays are the same. Per row
// the columns up < left < diagonal < right < down are already sorted in mask order.
template <typename Matrix>
void Assemble(const Grid& grid, const Edges& e, const std::vector<double>& anchor_weight,
              const std::vector<double>& anchor_value, Matrix* matrix, Eigen::VectorXd* rhs) {
  const int n = static_cast<int>(grid.size());
  std::size_t nonzeros = 0;
  for (int a = 0; a < n; ++a) {
    nonzeros +=
        1 + (grid.up[a] >= 0) + (grid.left[a] >= 0) + (grid.right[a] >= 0) + (grid.down[a] >= 0);
  }
  matrix->resize(n, n);
  matrix->resizeNonZeros(static_cast<Eigen::Index>(nonzeros));
  int* outer = matrix->outerIndexPtr();
  int* inner = matrix->innerIndexPtr();
  double* value = matrix->valuePtr();
  rhs->resize(n);
  int k = 0;
  for (int a = 0; a < n; ++a) {
    outer[a] = k;
    double diagonal = anchor_weight[a];
    double b = anchor_weight[a] * anchor_value[a];
    auto put = [&](int column, double w) {
      inner[k] = column;
      value[k++] = -w;
      diagonal += w;
    };
    if (const int u = grid.up[a]; u >= 0) {
      put(u, e.weight_down[u]);
      b += e.weight_down[u] * e.target_down[u];
    }
    if (const int l = grid.left[a]; l >= 0) {
      put(l, e.weight_right[l]);
      b += e.weight_right[l] * e.target_right[l];
    }
    const int diagonal_slot = k++;
    inner[diagonal_slot] = a;
    if (const int r = grid.right[a]; r >= 0) {
      put(r, e.weight_right[a]);
      b -= e.weight_right[a] * e.target_right[a];
    }
    if (const int d = grid.down[a]; d >= 0) {
      put(d, e.weight_down[a]);
      b -= e.weight_down[a] * e.target_down[a];
    }
    value[diagonal_slot] = diagonal;
    (*rhs)[a] = b;
  }
  outer[n] = k;
}

// Reusable solver for one sparsity pattern (the pattern does not change between rounds).
class LinearSystem {
 public:
  LinearSystem(const Grid& grid, const IntegrateOptions& options) : grid_(grid), options_(options) {
    // Multigrid CG wins at every size measured (bench_integrate): 3.4x the direct solvers at 50k
    // pixels, more beyond, as a 2D grid's Cholesky factor fills in like n log n.
    kind_ =
        options.solver == LinearSolver::kAuto ? LinearSolver::kConjugateGradient : options.solver;
#ifdef IPHONG_HAVE_CHOLMOD
    // AMD alone: CHOLMOD's default also tries METIS, slower than it gains on these sizes; the
    // simplicial factorization beats the supernodal one on grid Laplacians here.
    cholesky_.cholmod().nmethods = 1;
    cholesky_.cholmod().method[0].ordering = CHOLMOD_AMD;
#endif
  }

  std::string name() const {
    if (kind_ == LinearSolver::kConjugateGradient) return "conjugate-gradient (multigrid)";
#ifdef IPHONG_HAVE_CHOLMOD
    return "cholesky (cholmod)";
#else
    return "cholesky (eigen)";
#endif
  }

  // Assembles and solves, starting the iterative solver from `x`; returns CG iterations.
  long long Solve(const Edges& e, const std::vector<double>& anchor_weight,
                  const std::vector<double>& anchor_value, Eigen::VectorXd* x,
                  std::size_t* memory_bytes, const std::function<void(double)>& progress) {
    Eigen::VectorXd rhs;
    if (kind_ == LinearSolver::kConjugateGradient) {
      RowMatrix matrix;
      Assemble(grid_, e, anchor_weight, anchor_value, &matrix, &rhs);
      const GridMultigrid multigrid(matrix, grid_.col, grid_.row);
      const int iterations = SolvePcg(matrix, multigrid, rhs, options_.cg_tolerance,
                                      options_.cg_max_iterations, options_.threads, x, progress);
      *memory_bytes =
          std::max(*memory_bytes, multigrid.memory_bytes() + 5 * rhs.size() * sizeof(double));
      return iterations;
    }
    SparseMatrix matrix;
    Assemble(grid_, e, anchor_weight, anchor_value, &matrix, &rhs);
    if (!analysed_) {
      cholesky_.analyzePattern(matrix);
      analysed_ = true;
    }
    cholesky_.factorize(matrix);
    if (cholesky_.info() != Eigen::Success) throw std::runtime_error("the factorization failed");
    *x = cholesky_.solve(rhs);
    const std::size_t matrix_bytes =
        static_cast<std::size_t>(matrix.nonZeros()) * (sizeof(double) + sizeof(int));
    *memory_bytes = std::max(*memory_bytes, matrix_bytes + FactorBytes());
    return 0;
  }

 private:
  std::size_t FactorBytes() {
#ifdef IPHONG_HAVE_CHOLMOD
    // CHOLMOD's analysis records the factor's non-zeros.
    return static_cast<std::size_t>(cholesky_.cholmod().lnz) * (sizeof(double) + sizeof(int));
#else
    return static_cast<std::size_t>(cholesky_.matrixL().nestedExpression().nonZeros()) *
           (sizeof(double) + sizeof(int));
#endif
  }

  const Grid& grid_;
  const IntegrateOptions& options_;
  LinearSolver kind_;
  bool analysed_ = false;
#ifdef IPHONG_HAVE_CHOLMOD
  Eigen::CholmodSimplicialLLT<SparseMatrix> cholesky_;
#else
  Eigen::SimplicialLLT<SparseMatrix> cholesky_;
#endif
};

}  // namespace

SparseOutcome SolveMasked(const GridGradients& g, const Mask& mask,
                          const std::vector<double>& prior, const IntegrateOptions& options,
                          bool bilateral) {
  const Grid grid(mask);
  const std::size_t n = grid.size();
  SparseOutcome out;
  const std::vector<int> part =
      Components(grid, &out.components, [](std::size_t, int) { return true; });

  // Anchors: the prior where given; otherwise one pixel per part pinned at 0, which selects one
  // member of the part's family of solutions f + c without changing the others' residuals.
  std::vector<double> anchor_weight(n, 0), anchor_value(n, 0);
  std::vector<char> part_anchored(out.components, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isfinite(prior[i])) {
      anchor_weight[i] = options.prior_weight;
      anchor_value[i] = prior[i];
      part_anchored[part[i]] = 1;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!part_anchored[part[i]]) {
      anchor_weight[i] = 1;
      part_anchored[part[i]] = 1;
    }
  }

  OneSided u;
  u.forward_col.assign(n, 0.5), u.backward_col.assign(n, 0.5);
  u.forward_row.assign(n, 0.5), u.backward_row.assign(n, 0.5);
  LinearSystem system(grid, options);
  out.solver = system.name();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
  double previous_energy = std::numeric_limits<double>::infinity();
  const int rounds = bilateral ? options.max_rounds : 1;
  Edges edges;
  for (out.rounds = 1;; ++out.rounds) {
    edges = BuildEdges(grid, g, u);
    // Progress: the rounds in equal shares (one share without reweighting).
    std::function<void(double)> progress;
    if (options.progress) {
      progress = [&](double fraction) {
        options.progress((out.rounds - 1 + fraction) / static_cast<double>(rounds));
      };
    }
    out.iterations +=
        system.Solve(edges, anchor_weight, anchor_value, &f, &out.memory_bytes, progress);
    if (out.rounds >= rounds) break;

    // Residuals of the one-sided equations and the energy they weigh.
    double energy = 0;
    std::vector<double> r_fwd_col(n, 0), r_bwd_col(n, 0), r_fwd_row(n, 0), r_bwd_row(n, 0);
    for (std::size_t a = 0; a < n; ++a) {
      const int pa = grid.pixel[a];
      if (const int b = grid.right[a]; b >= 0) r_fwd_col[a] = f[b] - f[a] - g.d_col[pa];
      if (const int b = grid.left[a]; b >= 0) r_bwd_col[a] = f[a] - f[b] - g.d_col[pa];
      if (const int b = grid.down[a]; b >= 0) r_fwd_row[a] = f[b] - f[a] - g.d_row[pa];
      if (const int b = grid.up[a]; b >= 0) r_bwd_row[a] = f[a] - f[b] - g.d_row[pa];
      energy += u.forward_col[a] * r_fwd_col[a] * r_fwd_col[a] +
                u.backward_col[a] * r_bwd_col[a] * r_bwd_col[a] +
                u.forward_row[a] * r_fwd_row[a] * r_fwd_row[a] +
                u.backward_row[a] * r_bwd_row[a] * r_bwd_row[a];
    }
    if (std::abs(previous_energy - energy) <= options.energy_tolerance * energy) break;
    previous_energy = energy;
    // σ(k(r_other² − r_own²)); a missing side counts as a zero residual.
    // The stiffness is per pixel² in both cameras: under perspective a residual of log depth
    // times the focal length is the depth step in pixel widths at that depth (a pixel at depth d
    // spans d/f), so a step cuts alike whichever camera saw it.
    const double k_col =
        options.stiffness * (options.perspective ? Square(options.intrinsics.fx) : 1);
    const double k_row =
        options.stiffness * (options.perspective ? Square(options.intrinsics.fy) : 1);
    for (std::size_t a = 0; a < n; ++a) {
      const double fc = r_fwd_col[a] * r_fwd_col[a], bc = r_bwd_col[a] * r_bwd_col[a];
      const double fr = r_fwd_row[a] * r_fwd_row[a], br = r_bwd_row[a] * r_bwd_row[a];
      u.forward_col[a] = Sigmoid(k_col * (bc - fc));
      u.backward_col[a] = Sigmoid(k_col * (fc - bc));
      u.forward_row[a] = Sigmoid(k_row * (br - fr));
      u.backward_row[a] = Sigmoid(k_row * (fr - br));
    }
    // Heights toward the viewer (orthographic) or log depth away from it (perspective).
    const double toward_viewer = options.perspective ? -1.0 : 1.0;
    for (std::size_t i = 0; i < n; ++i) {
      const int a = static_cast<int>(i);
      if (const int b = grid.right[a]; b >= 0 && JoinedCrease(grid, g, g.d_col, a, b, f[b] - f[a],
                                                              options.min_cos, toward_viewer)) {
        u.forward_col[a] = u.backward_col[b] = 0.5;
      }
      if (const int b = grid.down[a]; b >= 0 && JoinedCrease(grid, g, g.d_row, a, b, f[b] - f[a],
                                                             options.min_cos, toward_viewer)) {
        u.forward_row[a] = u.backward_row[b] = 0.5;
      }
    }
  }

  // Continuity per edge and the residual of the final equations.
  out.continuity = ImageF(grid.width, grid.height, 2, 0.0f);
  double weighted = 0, weight_sum = 0;
  for (std::size_t a = 0; a < n; ++a) {
    float* c = out.continuity.pixels.data() + 2 * static_cast<std::size_t>(grid.pixel[a]);
    if (const int b = grid.right[a]; b >= 0) {
      c[0] = static_cast<float>(std::min(1.0, u.forward_col[a] + u.backward_col[b]));
      const double r = f[b] - f[a] - edges.target_right[a];
      weighted += edges.weight_right[a] * r * r;
      weight_sum += edges.weight_right[a];
    }
    if (const int b = grid.down[a]; b >= 0) {
      c[1] = static_cast<float>(std::min(1.0, u.forward_row[a] + u.backward_row[b]));
      const double r = f[b] - f[a] - edges.target_down[a];
      weighted += edges.weight_down[a] * r * r;
      weight_sum += edges.weight_down[a];
    }
  }
  out.rms_residual = weight_sum > 0 ? std::sqrt(weighted / weight_sum) : 0.0;

  // Cut edges, and the pixels they separate from the largest joined piece of their part: the
  // normals say nothing of how high such a piece sits against the rest.
  const auto joined = [&](std::size_t a, int axis) {
    return out.continuity.pixels[2 * static_cast<std::size_t>(grid.pixel[a]) + axis] >= 0.5f;
  };
  if (bilateral) {
    for (std::size_t a = 0; a < n; ++a) {
      out.cut_edges += (grid.right[a] >= 0 && !joined(a, 0)) + (grid.down[a] >= 0 && !joined(a, 1));
    }
  }
  if (out.cut_edges > 0) {
    int pieces = 0;
    const std::vector<int> piece = Components(grid, &pieces, joined);
    std::vector<std::size_t> piece_size(pieces, 0), largest(out.components, 0),
        part_size(out.components, 0);
    for (std::size_t i = 0; i < n; ++i) ++piece_size[piece[i]], ++part_size[part[i]];
    for (std::size_t i = 0; i < n; ++i) {
      largest[part[i]] = std::max(largest[part[i]], piece_size[piece[i]]);
    }
    for (int c = 0; c < out.components; ++c) out.separated_pixels += part_size[c] - largest[c];
  }

  // Parts without a prior: mean 0.
  std::vector<double> sum(out.components, 0), count(out.components, 0);
  std::vector<char> has_prior(out.components, 0);
  for (std::size_t i = 0; i < n; ++i) {
    sum[part[i]] += f[i];
    count[part[i]] += 1;
    if (std::isfinite(prior[i])) has_prior[part[i]] = 1;
  }
  out.f.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.f[i] = has_prior[part[i]] ? f[i] : f[i] - sum[part[i]] / count[part[i]];
  }
  return out;
}

}  // namespace iphong::integrate::internal
