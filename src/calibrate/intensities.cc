// Semi-calibrated photometric stereo: the lights' intensities from the images and directions.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "calibrate/lights.h"
#include "core/parallel.h"
#include "core/timing.h"

namespace iphong::calibrate {

std::string IntensityOptions::Check() const {
  if (!(discard_dark >= 0 && discard_bright >= 0 && discard_dark + discard_bright < 0.9)) {
    return "discard_dark and discard_bright must be non-negative and leave a tenth of the lights";
  }
  if (rounds < 1 || rounds > 20) return "rounds must be 1 to 20";
  return "";
}

IntensityEstimate EstimateIntensities(const solve::PhotometricData& data,
                                      const IntensityOptions& options) {
  const auto start = Clock::now();
  if (std::string m = options.Check(); !m.empty()) throw std::invalid_argument(m);
  if (std::string m = data.Validate(); !m.empty()) throw std::invalid_argument(m);
  const int k = data.images;
  if (k < 4) {
    throw std::invalid_argument("estimating intensities needs 4 images or more (got " +
                                std::to_string(k) + ")");
  }
  const std::size_t pixels = data.pixel_count();
  const int first = static_cast<int>(std::floor(options.discard_dark * k));
  const int last = k - static_cast<int>(std::floor(options.discard_bright * k));
  if (last - first < 4) throw std::invalid_argument("too few lights kept per pixel");
  Eigen::MatrixX3d lights(k, 3);
  for (int j = 0; j < k; ++j) lights.row(j) = data.light_directions[j].transpose();

  IntensityEstimate result;
  Eigen::MatrixXd u = Eigen::MatrixXd::Ones(k, 3);  // 1 / E_jc
  std::vector<double> residual(pixels, 0), pixel_weight(pixels, 1.0);
  const int workers = std::max(1, std::min<int>(ResolveThreads(options.threads), 64));
  double gap = std::numeric_limits<double>::infinity();
  for (int round = 0; round < options.rounds; ++round) {
    std::vector<std::array<Eigen::MatrixXd, 3>> sums(workers);
    ParallelFor(0, workers, 1, options.threads, [&](std::size_t w0, std::size_t w1) {
      for (std::size_t t = w0; t < w1; ++t) {
        for (auto& a : sums[t]) a = Eigen::MatrixXd::Zero(k, k);
        std::vector<int> order(k);
        std::vector<double> y(k);
        const std::size_t p0 = pixels * t / workers, p1 = pixels * (t + 1) / workers;
        for (std::size_t p = p0; p < p1; ++p) {
          const float* v = data.pixel(p);
          for (int j = 0; j < k; ++j)
            y[j] = (v[3 * j] * u(j, 0) + v[3 * j + 1] * u(j, 1) + v[3 * j + 2] * u(j, 2)) / 3;
          std::iota(order.begin(), order.end(), 0);
          std::sort(order.begin(), order.end(), [&](int a, int b) { return y[a] < y[b]; });
          const int n = last - first;
          Eigen::MatrixX3d ls(n, 3);
          Eigen::VectorXd ys(n);
          for (int i = 0; i < n; ++i) {
            ls.row(i) = lights.row(order[first + i]);
            ys(i) = y[order[first + i]];
          }
          const Eigen::Matrix3d normal = ls.transpose() * ls;
          Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
          if (ldlt.info() != Eigen::Success || std::abs(normal.determinant()) < 1e-9) {
            pixel_weight[p] = 0;
            continue;
          }
          const Eigen::MatrixXd projector =
              Eigen::MatrixXd::Identity(n, n) - ls * ldlt.solve(ls.transpose());
          const Eigen::Vector3d m = ldlt.solve(ls.transpose() * ys);
          residual[p] = m.norm() > 0 ? (ys - ls * m).norm() / std::sqrt(double(n)) / m.norm()
                                     : std::numeric_limits<double>::infinity();
          if (pixel_weight[p] <= 0) continue;
          for (int c = 0; c < 3; ++c) {
            Eigen::VectorXd d(n);
            for (int i = 0; i < n; ++i) d(i) = v[3 * order[first + i] + c];
            const Eigen::MatrixXd term =
                pixel_weight[p] * projector.cwiseProduct(d * d.transpose());
            for (int a = 0; a < n; ++a)
              for (int b = 0; b < n; ++b)
                sums[t][c](order[first + a], order[first + b]) += term(a, b);
          }
        }
      }
    });
    for (int c = 0; c < 3; ++c) {
      Eigen::MatrixXd a = Eigen::MatrixXd::Zero(k, k);
      for (const auto& s : sums) a += s[c];
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
      Eigen::VectorXd smallest = eigen.eigenvectors().col(0);
      if (smallest.sum() < 0) smallest = -smallest;
      u.col(c) = smallest;
      const double l0 = std::max(eigen.eigenvalues()(0), 1e-300);
      gap = std::min(gap, eigen.eigenvalues()(1) / l0);
    }
    // Next round: pixels weighted by how well Lambert explains their kept observations.
    std::vector<double> finite;
    for (std::size_t p = 0; p < pixels; ++p)
      if (std::isfinite(residual[p])) finite.push_back(residual[p]);
    if (finite.empty()) break;
    std::nth_element(finite.begin(), finite.begin() + finite.size() / 2, finite.end());
    const double median = std::max(finite[finite.size() / 2], 1e-12);
    for (std::size_t p = 0; p < pixels; ++p) {
      pixel_weight[p] =
          std::isfinite(residual[p]) ? 1 / (residual[p] * residual[p] + median * median) : 0;
    }
    result.rounds = round + 1;
  }
  result.eigen_gap = gap;
  result.light_intensities.assign(k, Rgb::Ones());
  for (int c = 0; c < 3; ++c) {
    // An eigenvector with entries of both signs means no positive solution: the data are not
    // Lambertian enough, and the intensities stay 1 for that channel.
    if (u.col(c).minCoeff() <= 0) {
      result.note += std::string(result.note.empty() ? "" : "; ") + "RGB"[c] +
                     ": no positive solution (the data are far from Lambertian); left at 1";
      continue;
    }
    double mean = 0;
    for (int j = 0; j < k; ++j) mean += 1 / u(j, c) / k;
    for (int j = 0; j < k; ++j) result.light_intensities[j][c] = 1 / u(j, c) / mean;
  }
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace iphong::calibrate
