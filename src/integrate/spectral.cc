// Poisson solvers on the full rectangle, with OpenCV's DCT and DFT.
//
// The normal equations of the edge problem are L f = b with L the graph Laplacian of the grid
// and b_i = Σ over i's edges of ±target (+ when i is the edge's second pixel). On a path of n
// nodes the Neumann graph Laplacian is diagonalised by the DCT-II with eigenvalues
// 2 − 2cos(πk/n); on a cycle by the DFT with 2 − 2cos(2πk/n). The 2D operators are Kronecker
// sums, so one forward transform, a division and one inverse transform solve the system exactly.
#include <opencv2/core.hpp>

#include <cmath>

#include "integrate/internal.h"

namespace iphong::integrate::internal {
namespace {

// b for the edge equations; `periodic` adds the wrap-around edges.
cv::Mat Divergence(const GridGradients& g, bool periodic) {
  const int w = g.width, h = g.height;
  cv::Mat b(h, w, CV_64F, cv::Scalar(0));
  auto at = [&](int c, int r) { return static_cast<std::size_t>(r) * w + c; };
  for (int r = 0; r < h; ++r) {
    double* row = b.ptr<double>(r);
    for (int c = 0; c < w; ++c) {
      const bool wrap_c = c + 1 == w;
      if (!wrap_c || (periodic && w > 1)) {
        const int c2 = wrap_c ? 0 : c + 1;
        const double t = 0.5 * (g.d_col[at(c, r)] + g.d_col[at(c2, r)]);
        row[c] -= t;
        row[c2] += t;
      }
      const bool wrap_r = r + 1 == h;
      if (!wrap_r || (periodic && h > 1)) {
        const int r2 = wrap_r ? 0 : r + 1;
        const double t = 0.5 * (g.d_row[at(c, r)] + g.d_row[at(c, r2)]);
        row[c] -= t;
        b.ptr<double>(r2)[c] += t;
      }
    }
  }
  return b;
}

// Divides each coefficient (row r, column c) of a spectrum by the Laplacian's eigenvalue
// (2 − 2cos(a·c/w)) + (2 − 2cos(a·r/h)), a = π for the DCT-II, 2π for the DFT; the constant
// mode (eigenvalue 0) is set to 0, which fixes the mean.
template <typename Coefficient>
void DivideByEigenvalues(cv::Mat& spectrum, double a) {
  const int h = spectrum.rows, w = spectrum.cols;
  std::vector<double> lx(w), ly(h);
  for (int k = 0; k < w; ++k) lx[k] = 2 - 2 * std::cos(a * k / w);
  for (int k = 0; k < h; ++k) ly[k] = 2 - 2 * std::cos(a * k / h);
  for (int r = 0; r < h; ++r) {
    auto* row = spectrum.ptr<Coefficient>(r);
    for (int c = 0; c < w; ++c) {
      const double lambda = lx[c] + ly[r];
      row[c] = lambda > 0 ? row[c] * (1 / lambda) : Coefficient();
    }
  }
}

// Solves (graph Laplacian of the torus) f = b for b with zero sum; the result has zero mean.
cv::Mat SolvePeriodic(const cv::Mat& b) {
  cv::Mat spectrum;
  cv::dft(b, spectrum, cv::DFT_COMPLEX_OUTPUT);
  DivideByEigenvalues<cv::Vec2d>(spectrum, 2 * M_PI);
  cv::Mat f;
  cv::idft(spectrum, f, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  return f;
}

std::vector<double> ToVector(const cv::Mat& f) {
  std::vector<double> out(static_cast<std::size_t>(f.rows) * f.cols);
  for (int r = 0; r < f.rows; ++r) {
    const double* row = f.ptr<double>(r);
    std::copy(row, row + f.cols, out.begin() + static_cast<std::size_t>(r) * f.cols);
  }
  return out;
}

}  // namespace

std::vector<double> SolveRectangleNeumann(const GridGradients& g) {
  const cv::Mat b = Divergence(g, false);
  const int h = b.rows, w = b.cols;
  if (w % 2 == 0 && h % 2 == 0) {
    cv::Mat spectrum;
    cv::dct(b, spectrum);
    DivideByEigenvalues<double>(spectrum, M_PI);
    cv::Mat f;
    cv::idct(spectrum, f);
    return ToVector(f);
  }
  // The half-sample-symmetric extension turns the Neumann problem into a periodic one of twice
  // the size whose solution is symmetric and equals the Neumann solution on the first quadrant.
  cv::Mat mirrored(2 * h, 2 * w, CV_64F);
  cv::Mat flipped;
  b.copyTo(mirrored(cv::Rect(0, 0, w, h)));
  cv::flip(b, flipped, 1);
  flipped.copyTo(mirrored(cv::Rect(w, 0, w, h)));
  cv::flip(b, flipped, 0);
  flipped.copyTo(mirrored(cv::Rect(0, h, w, h)));
  cv::flip(b, flipped, -1);
  flipped.copyTo(mirrored(cv::Rect(w, h, w, h)));
  return ToVector(SolvePeriodic(mirrored)(cv::Rect(0, 0, w, h)).clone());
}

std::vector<double> SolveRectanglePeriodic(const GridGradients& g) {
  return ToVector(SolvePeriodic(Divergence(g, true)));
}

}  // namespace iphong::integrate::internal
