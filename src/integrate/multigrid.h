// Conjugate gradients preconditioned by an aggregation multigrid V-cycle, for the graph
// Laplacians of pixel grids (any mask). Direct Cholesky fill grows like n·log n on 2D grids and
// plain or incomplete-Cholesky CG needs thousands of iterations at megapixel size; a V-cycle
// keeps the iteration count nearly independent of the size.
//
// Levels: unknowns are grouped by 2×2 pixel blocks (col/2, row/2); the coarse operator is the
// Galerkin product PᵀAP with piecewise-constant P, again a graph Laplacian (plus the anchors),
// down to a few hundred unknowns solved directly. Smoothing: forward Gauss–Seidel before,
// backward after, so the preconditioner is symmetric.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <memory>
#include <vector>

namespace iphong::integrate::internal {

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

class GridMultigrid {
 public:
  // `a` must be symmetric positive definite and outlive the preconditioner (its finest level
  // reads it); col/row give each unknown's pixel.
  GridMultigrid(const RowMatrix& a, const std::vector<int>& col, const std::vector<int>& row);
  ~GridMultigrid();
  // z ≈ A⁻¹ r by one V-cycle. Not for concurrent use (the levels hold the work vectors).
  void Apply(const Eigen::VectorXd& r, Eigen::VectorXd* z) const;
  std::size_t memory_bytes() const;

 private:
  struct Level;
  std::vector<std::unique_ptr<Level>> levels_;
  void Cycle(std::size_t l) const;
};

// Solves A x = b from the starting point in `x` to ‖b − Ax‖ ≤ tolerance·‖b‖; returns the
// iterations. SpMV runs on `threads`.
// `progress`, when set, gets log(‖r‖/‖b‖)/log(tolerance) after each iteration.
int SolvePcg(const RowMatrix& a, const GridMultigrid& preconditioner, const Eigen::VectorXd& b,
             double tolerance, int max_iterations, int threads, Eigen::VectorXd* x,
             const std::function<void(double)>& progress = {});

}  // namespace iphong::integrate::internal
