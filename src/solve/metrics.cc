#include "solve/metrics.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace iphong::solve {

AngularErrorMetrics CompareNormals(const ImageF& estimate, const ImageF& ground_truth,
                                   const Mask& mask) {
  if (estimate.width != ground_truth.width || estimate.height != ground_truth.height ||
      estimate.channels < 3 || ground_truth.channels < 3 || mask.width != estimate.width ||
      mask.height != estimate.height) {
    throw std::invalid_argument("estimate, ground truth and mask differ in size");
  }
  AngularErrorMetrics m;
  m.error_deg = ImageF(estimate.width, estimate.height, 1);
  std::vector<double> errors;
  for (std::size_t p = 0; p < estimate.pixel_count(); ++p) {
    if (!mask.inside[p]) continue;
    const float* e = estimate.pixels.data() + p * estimate.channels;
    const float* g = ground_truth.pixels.data() + p * ground_truth.channels;
    const Vec3d a(e[0], e[1], e[2]), b(g[0], g[1], g[2]);
    if (!(b.norm() > 0.5)) continue;  // no ground truth here
    const bool finite = a.allFinite();
    if (!finite && m.not_finite++ == 0) m.first_not_finite = p;
    // atan2 of |a×b| and a·b is accurate for tiny angles, where acos loses digits.
    const bool some = finite && a.norm() > 0;
    m.missing += !some;
    const double angle = some ? std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI : 180.0;
    errors.push_back(angle);
    m.error_deg.pixels[p] = static_cast<float>(angle);
  }
  if (errors.empty()) throw std::invalid_argument("no pixel has both an estimate and ground truth");
  if (m.missing == errors.size()) {  // every pixel missing: a blank map or another file
    const std::string n = std::to_string(errors.size());
    throw std::invalid_argument(
        m.not_finite == errors.size()
            ? "holds no finite normal where the ground truth has one (NaN or infinite at all " + n +
                  " such pixels; the first at column " +
                  std::to_string(m.first_not_finite % estimate.width) + ", row " +
                  std::to_string(m.first_not_finite / estimate.width) + ")"
            : "holds no normal where the ground truth has one (0" +
                  std::string(m.not_finite > 0 ? ", NaN or infinite" : "") + " at all " + n +
                  " such pixels)");
  }
  m.pixels = errors.size();
  double sum = 0;
  for (double e : errors) {
    sum += e;
    m.below_5_deg += e < 5;
    m.below_10_deg += e < 10;
    m.below_20_deg += e < 20;
  }
  const double n = static_cast<double>(errors.size());
  m.mean_deg = sum / n;
  m.below_5_deg /= n;
  m.below_10_deg /= n;
  m.below_20_deg /= n;
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  m.median_deg = errors[errors.size() / 2];
  if (errors.size() % 2 == 0) {
    m.median_deg = 0.5 * (m.median_deg +
                          *std::max_element(errors.begin(), errors.begin() + errors.size() / 2));
  }
  return m;
}

}  // namespace iphong::solve
