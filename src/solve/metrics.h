// Angular error between estimated and ground-truth normal maps, the standard figures of
// photometric-stereo benchmarks (DiLiGenT reports the mean).
#pragma once

#include <string>
#include <vector>

#include "core/types.h"

namespace iphong::solve {

struct AngularErrorMetrics {
  std::size_t pixels = 0;
  double mean_deg = 0;
  double median_deg = 0;
  double below_5_deg = 0;  // fraction of pixels
  double below_10_deg = 0;
  double below_20_deg = 0;
  // Evaluated pixels whose estimate is not finite (NaN or infinite: other tools write NaN where
  // they found no normal), scored as missing (180°) as a zero estimate is; the first of them
  // (row-major pixel index) when there are any.
  std::size_t not_finite = 0;
  std::size_t first_not_finite = 0;
  // Evaluated pixels with no normal in the estimate, scored 180°: a zero vector (how iphong and
  // DiLiGenT's maps mark "none") or not finite (counted in not_finite too).
  std::size_t missing = 0;
  ImageF error_deg;  // 1 channel, 0 outside the evaluated pixels
};

// Over the pixels inside `mask` where the ground truth is a non-zero vector. Both maps are
// 3-channel xyz. Throws std::invalid_argument on size mismatch, an empty evaluation set or an
// estimate with no normal on it (0, NaN or infinite wherever the ground truth has one: a mean of
// 180° is no method's, but a wrong file or a blank map).
AngularErrorMetrics CompareNormals(const ImageF& estimate, const ImageF& ground_truth,
                                   const Mask& mask);

}  // namespace iphong::solve
