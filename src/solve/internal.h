// Pieces shared by the solvers of src/solve (not part of the public interface).
#pragma once

#include <vector>

#include "core/types.h"
#include "reflectance/phong.h"

namespace iphong::solve::internal {

// The orthographic view direction of photometric stereo (SPEC.md).
inline Vec3d ViewCam() { return Vec3d(0, 0, 1); }

// Rec. 709 luminance of linear RGB: linear, so it commutes with the model.
inline double Luminance(const Vec3d& rgb) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

// The albedo minimizing Σ_j w_j (y_j − kd·diffuse_j − ks·specular_j)², clamped at 0: the
// variable-projection step of every fit. y(j) and weight(j) give observation j and its weight.
template <typename T, typename Y, typename Weight>
T EliminatedAlbedo(const std::vector<reflectance::LightFactors<T>>& factors, const T& ks, Y y,
                   Weight weight) {
  T num = T(0), den = T(0);
  for (std::size_t j = 0; j < factors.size(); ++j) {
    const double w = weight(j);
    if (w == 0) continue;
    num += T(w) * factors[j].diffuse * (y(j) - ks * factors[j].specular);
    den += T(w) * factors[j].diffuse * factors[j].diffuse;
  }
  const T kd = den > T(1e-12) ? num / den : T(0);
  return kd < T(0) ? T(0) : kd;
}

}  // namespace iphong::solve::internal
