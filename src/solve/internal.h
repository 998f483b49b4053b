// Pieces shared by the solvers of src/solve (not part of the public interface).
#pragma once

#include <array>
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

// The albedo minimizing Σ_j w_j (y_jc − kd_c·diffuse_j − ks_c·specular_j)² for each of
// `channels` (≤ 3) channels, clamped at 0: the variable-projection step of every fit,
//   kd_c = (Σ w d y_c − ks_c Σ w d s) / Σ w d²,
// in one pass over the lights. y(j, c) is observation j of channel c (a plain number or a T),
// ks(c) the channel's specular coefficient, weight(j) the observation's weight.
template <typename T, typename Ks, typename Y, typename Weight>
std::array<T, 3> EliminatedAlbedo(const std::vector<reflectance::LightFactors<T>>& factors,
                                  int channels, Ks ks, Y y, Weight weight) {
  T den = T(0), cross = T(0);
  std::array<T, 3> kd = {T(0), T(0), T(0)};  // Σ w d y_c until the end
  for (std::size_t j = 0; j < factors.size(); ++j) {
    const double w = weight(j);
    if (w == 0) continue;
    const T wd = w * factors[j].diffuse;
    den += wd * factors[j].diffuse;
    cross += wd * factors[j].specular;
    for (int c = 0; c < channels; ++c) kd[c] += wd * y(j, c);
  }
  for (int c = 0; c < channels; ++c) {
    kd[c] = den > T(1e-12) ? (kd[c] - ks(c) * cross) / den : T(0);
    if (kd[c] < T(0)) kd[c] = T(0);
  }
  return kd;
}

}  // namespace iphong::solve::internal
