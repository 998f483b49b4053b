#include "integrate/multigrid.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>

#include "core/parallel.h"

namespace iphong::integrate::internal {

struct GridMultigrid::Level {
  const RowMatrix* a = nullptr;  // the caller's matrix on the finest level, `own` below it
  RowMatrix own;
  Eigen::VectorXd inverse_diagonal;
  std::vector<int> parent;  // coarse unknown of each unknown (empty on the coarsest level)
  Eigen::LDLT<Eigen::MatrixXd> direct;  // coarsest level only
  Eigen::VectorXd b, x, residual;       // work vectors of a cycle
};

namespace {

constexpr int kCoarsest = 400;
// Piecewise-constant aggregation makes the coarse correction too small (its operator is about
// twice too stiff); scaling the correction is the standard remedy.
constexpr double kOverCorrection = 1.8;

void ForwardGaussSeidel(const RowMatrix& a, const Eigen::VectorXd& inv_diag,
                        const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  const int n = static_cast<int>(a.rows());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  for (int i = 0; i < n; ++i) {
    double s = b[i];
    for (int k = outer[i]; k < outer[i + 1]; ++k) {
      if (inner[k] != i) s -= value[k] * (*x)[inner[k]];
    }
    (*x)[i] = s * inv_diag[i];
  }
}

void BackwardGaussSeidel(const RowMatrix& a, const Eigen::VectorXd& inv_diag,
                         const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  for (int i = static_cast<int>(a.rows()) - 1; i >= 0; --i) {
    double s = b[i];
    for (int k = outer[i]; k < outer[i + 1]; ++k) {
      if (inner[k] != i) s -= value[k] * (*x)[inner[k]];
    }
    (*x)[i] = s * inv_diag[i];
  }
}

// r = b − A x, written in place (Eigen's sparse product would allocate a temporary per cycle).
void Residual(const RowMatrix& a, const Eigen::VectorXd& b, const Eigen::VectorXd& x,
              Eigen::VectorXd* r) {
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    double s = b[i];
    for (int k = outer[i]; k < outer[i + 1]; ++k) s -= value[k] * x[inner[k]];
    (*r)[i] = s;
  }
}

void Multiply(const RowMatrix& a, const Eigen::VectorXd& x, int threads, Eigen::VectorXd* y) {
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  ParallelFor(0, static_cast<std::size_t>(a.rows()), 1 << 16, threads,
              [&](std::size_t begin, std::size_t end) {
                for (std::size_t i = begin; i < end; ++i) {
                  double s = 0;
                  for (int k = outer[i]; k < outer[i + 1]; ++k) s += value[k] * x[inner[k]];
                  (*y)[i] = s;
                }
              });
}

}  // namespace

GridMultigrid::GridMultigrid(const RowMatrix& a, const std::vector<int>& col,
                             const std::vector<int>& row) {
  // The finest level reads the caller's matrix: a copy of it was the largest allocation here.
  const RowMatrix* finest = &a;
  RowMatrix current;
  std::vector<int> c = col, r = row;
  for (;;) {
    auto level = std::make_unique<Level>();
    if (finest) {
      level->a = finest, finest = nullptr;
    } else {
      level->own = std::move(current);
      level->a = &level->own;
    }
    level->inverse_diagonal = level->a->diagonal().cwiseInverse();
    const int n = static_cast<int>(level->a->rows());
    level->b.resize(n), level->x.resize(n), level->residual.resize(n);
    if (n <= kCoarsest) {
      level->direct.compute(Eigen::MatrixXd(*level->a));
      levels_.push_back(std::move(level));
      break;
    }
    // Aggregates: 2×2 pixel blocks, numbered in row-major block order.
    const int block_cols = *std::max_element(c.begin(), c.end()) / 2 + 1;
    const int block_rows = *std::max_element(r.begin(), r.end()) / 2 + 1;
    std::vector<int> block(static_cast<std::size_t>(block_cols) * block_rows, -1);
    for (int i = 0; i < n; ++i)
      block[static_cast<std::size_t>(r[i] / 2) * block_cols + c[i] / 2] = 0;
    std::vector<int> cc, cr;
    for (std::size_t k = 0; k < block.size(); ++k) {
      if (block[k] < 0) continue;
      block[k] = static_cast<int>(cc.size());
      cc.push_back(static_cast<int>(k % block_cols));
      cr.push_back(static_cast<int>(k / block_cols));
    }
    const int coarse = static_cast<int>(cc.size());
    level->parent.resize(n);
    for (int i = 0; i < n; ++i) {
      level->parent[i] = block[static_cast<std::size_t>(r[i] / 2) * block_cols + c[i] / 2];
    }
    if (coarse == n) {  // nothing merges any more (isolated pixels): solve here
      level->parent.clear();
      level->direct.compute(Eigen::MatrixXd(*level->a));
      levels_.push_back(std::move(level));
      break;
    }
    // Galerkin PᵀAP row by row: a coarse row sums its (at most 4) children's rows, whose
    // columns fall in the 3×3 neighbouring blocks.
    std::vector<int> child_start(coarse + 1, 0), children(n);
    for (int i = 0; i < n; ++i) ++child_start[level->parent[i] + 1];
    for (int k = 0; k < coarse; ++k) child_start[k + 1] += child_start[k];
    {
      std::vector<int> fill(child_start.begin(), child_start.end() - 1);
      for (int i = 0; i < n; ++i) children[fill[level->parent[i]]++] = i;
    }
    std::vector<int> outer(coarse + 1, 0), inner;
    std::vector<double> value;
    inner.reserve(static_cast<std::size_t>(coarse) * 9);
    value.reserve(static_cast<std::size_t>(coarse) * 9);
    std::array<std::pair<int, double>, 16> row_entries;
    for (int k = 0; k < coarse; ++k) {
      int count = 0;
      for (int j = child_start[k]; j < child_start[k + 1]; ++j) {
        for (RowMatrix::InnerIterator it(*level->a, children[j]); it; ++it) {
          const int column = level->parent[it.col()];
          int slot = 0;
          while (slot < count && row_entries[slot].first != column) ++slot;
          if (slot == count) row_entries[count++] = {column, 0.0};
          row_entries[slot].second += it.value();
        }
      }
      std::sort(row_entries.begin(), row_entries.begin() + count);
      for (int e = 0; e < count; ++e) {
        inner.push_back(row_entries[e].first);
        value.push_back(row_entries[e].second);
      }
      outer[k + 1] = static_cast<int>(inner.size());
    }
    current = Eigen::Map<const RowMatrix>(coarse, coarse, static_cast<Eigen::Index>(inner.size()),
                                          outer.data(), inner.data(), value.data());
    c = std::move(cc), r = std::move(cr);
    levels_.push_back(std::move(level));
  }
}

GridMultigrid::~GridMultigrid() = default;

std::size_t GridMultigrid::memory_bytes() const {
  std::size_t bytes = 0;
  for (const auto& l : levels_) {
    bytes += l->a->nonZeros() * (sizeof(double) + sizeof(int)) + l->a->rows() * 3 * sizeof(double) +
             l->parent.size() * sizeof(int);
  }
  return bytes;
}

// Solves level l's system for its `b` into its `x`; the work vectors live in the levels so a
// cycle allocates nothing (fresh pages cost more than the arithmetic at megapixel size).
void GridMultigrid::Cycle(std::size_t l) const {
  Level& level = *levels_[l];
  if (level.parent.empty()) {
    level.x = level.direct.solve(level.b);
    return;
  }
  Level& coarse = *levels_[l + 1];
  level.x.setZero();
  ForwardGaussSeidel(*level.a, level.inverse_diagonal, level.b, &level.x);
  Residual(*level.a, level.b, level.x, &level.residual);
  coarse.b.setZero();
  for (Eigen::Index i = 0; i < level.b.size(); ++i) coarse.b[level.parent[i]] += level.residual[i];
  Cycle(l + 1);
  for (Eigen::Index i = 0; i < level.b.size(); ++i) {
    level.x[i] += kOverCorrection * coarse.x[level.parent[i]];
  }
  BackwardGaussSeidel(*level.a, level.inverse_diagonal, level.b, &level.x);
}

void GridMultigrid::Apply(const Eigen::VectorXd& r, Eigen::VectorXd* z) const {
  levels_[0]->b = r;
  Cycle(0);
  *z = levels_[0]->x;
}

int SolvePcg(const RowMatrix& a, const GridMultigrid& preconditioner, const Eigen::VectorXd& b,
             double tolerance, int max_iterations, int threads, Eigen::VectorXd* x,
             const std::function<void(double)>& progress) {
  const double b_norm = b.norm();
  if (b_norm == 0) {
    x->setZero(b.size());
    return 0;
  }
  Eigen::VectorXd ax(b.size()), r, z, p, ap(b.size());
  Multiply(a, *x, threads, &ax);
  r = b - ax;
  preconditioner.Apply(r, &z);
  p = z;
  double rz = r.dot(z);
  int iteration = 0;
  while (iteration < max_iterations && r.norm() > tolerance * b_norm) {
    Multiply(a, p, threads, &ap);
    const double alpha = rz / p.dot(ap);
    *x += alpha * p;
    r -= alpha * ap;
    preconditioner.Apply(r, &z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
    ++iteration;
    if (progress) {
      progress(std::clamp(std::log(r.norm() / b_norm) / std::log(tolerance), 0.0, 1.0));
    }
  }
  return iteration;
}

}  // namespace iphong::integrate::internal
