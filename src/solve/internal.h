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
// With `specular_scale`, ks is scaled by one more unknown σ ≥ 0 shared by the channels, found in
// the same pass: substituting kd_c(σ) leaves a linear equation in σ (with a prior λ(σ − 1)²Σks²),
//   σ Σ_c ks_c² (S − X²/D + λ) = Σ_c ks_c (B_c − A_c X/D) + λ Σ_c ks_c²,
// with D = Σ w d², X = Σ w d s, S = Σ w s², A_c = Σ w d y_c, B_c = Σ w s y_c.
template <typename T, typename Ks, typename Y, typename Weight>
std::array<T, 3> EliminatedAlbedo(const std::vector<reflectance::LightFactors<T>>& factors,
                                  int channels, Ks ks, Y y, Weight weight,
                                  T* specular_scale = nullptr, double scale_prior = 1) {
  T d = T(0), x = T(0), s = T(0);
  std::array<T, 3> a = {T(0), T(0), T(0)}, b = {T(0), T(0), T(0)};
  for (std::size_t j = 0; j < factors.size(); ++j) {
    const double w = weight(j);
    if (w == 0) continue;
    const T wd = w * factors[j].diffuse;
    d += wd * factors[j].diffuse;
    x += wd * factors[j].specular;
    for (int c = 0; c < channels; ++c) a[c] += wd * y(j, c);
    if (specular_scale) {
      const T ws = w * factors[j].specular;
      s += ws * factors[j].specular;
      for (int c = 0; c < channels; ++c) b[c] += ws * y(j, c);
    }
  }
  if (!(d > T(1e-12))) {
    if (specular_scale) *specular_scale = T(1);
    return {T(0), T(0), T(0)};
  }
  T sigma = T(1);
  if (specular_scale) {
    // The prior toward the estimated strength (σ = 1), worth λ observations of the lobe's peak:
    // a pixel that sees no highlight keeps σ near 1 instead of dividing noise by nothing.
    T num = T(0), den = T(0);
    for (int c = 0; c < channels; ++c) {
      num += ks(c) * (b[c] - a[c] * x / d) + scale_prior * ks(c) * ks(c);
      den += ks(c) * ks(c) * (s - x * x / d + T(scale_prior));
    }
    sigma = den > T(1e-24) ? num / den : T(1);
    if (sigma < T(0)) sigma = T(0);
    *specular_scale = sigma;
  }
  std::array<T, 3> kd = {T(0), T(0), T(0)};
  for (int c = 0; c < channels; ++c) {
    kd[c] = (a[c] - sigma * ks(c) * x) / d;
    if (kd[c] < T(0)) kd[c] = T(0);
  }
  return kd;
}

}  // namespace iphong::solve::internal
