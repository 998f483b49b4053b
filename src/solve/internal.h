// Pieces shared by the solvers of src/solve (not part of the public interface).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
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

// The linear coefficients of one channel's fit y_j ≈ kd·d_j + ks·s_j, both ≥ 0.
template <typename T>
struct CoefficientPair {
  T kd = T(0);
  T ks = T(0);
};

// Non-negative least squares in (kd, ks) from the weighted sums D = Σ w d², X = Σ w d s,
// S = Σ w s², A = Σ w d y, B = Σ w s y: the free solution of [D X; X S][kd ks]ᵀ = [A B]ᵀ when
// it lies in the quadrant, else the better of the two one-coefficient fits (their cost falls
// by A²/D and B²/S). Where s is (nearly) a multiple of d, or absent, ks = 0: the lobe cannot be
// told from the diffuse term there. Branches are on values, so a Jet carries the derivative of
// whichever branch applies.
//
// A prior λ(ks − ks0)² (λ in observations of the lobe's peak) enters as S + λ and B + λ·ks0.
//
// ks is always pulled toward 0 with kKsRidge too. A pixel no light shows near its lobe's peak
// sees only the lobe's far tail (Blinn-Phong n 922 is 10⁻⁶ of its peak at 10°), and the free
// least squares scales that tail up to fit interreflections and noise: ks of 10⁶ to 10²⁶ came
// out on every DiLiGenT object (a tenth of the ball's pixels above 10), and a tail that steep
// pulls the normal. The ridge is one observation at 3 % of the peak: where a light shows the
// lobe above that, ks is as before; where none does, ks stays small (the weights measured:
// docs/accuracy.md).
constexpr double kKsRidge = 1e-3;

template <typename T>
CoefficientPair<T> NonNegativePair(const T& d, const T& x, const T& s_data, const T& a,
                                   const T& b_data, double prior_weight = 0, double prior_ks = 0,
                                   double ridge = kKsRidge) {
  const T s = s_data + prior_weight + ridge;
  const T b = b_data + prior_weight * prior_ks;
  CoefficientPair<T> c;
  const T det = d * s - x * x;
  if (det > T(1e-9) * d * s && d > T(1e-12)) {
    const T kd = (a * s - b * x) / det;
    const T ks = (b * d - a * x) / det;
    if (kd >= T(0) && ks >= T(0)) return {kd, ks};
  }
  const bool diffuse_ok = d > T(1e-12) && a > T(0);
  const bool specular_ok = s > T(1e-12) && b > T(0) && det > T(1e-9) * d * s;
  const T gain_d = diffuse_ok ? a * a / d : T(0);
  const T gain_s = specular_ok ? b * b / s : T(0);
  if (diffuse_ok && !(gain_s > gain_d)) c.kd = a / d;
  if (specular_ok && gain_s > gain_d) c.ks = b / s;
  return c;
}

// The coefficients minimizing Σ_j w_j (y_jc − kd_c·d_j − ks_c·s_j)² for each of `channels` (≤ 3)
// channels, all ≥ 0: the variable-projection step of every fit. With `fixed_ks` (known
// coefficients) only kd_c = (A_c − ks_c X)/D is solved, clamped at 0; otherwise both per channel
// (NonNegativePair), so a specular colour of any hue — white on plastic, the surface's own on
// metal — is found rather than assumed. y(j, c) is observation j of channel c (a number or a T),
// weight(j) its weight, factors[j] the model's (d_j, s_j).
// With `prior_ks` (free ks only), each channel's ks is pulled toward prior_ks[c] with weight
// `prior_weight` (NonNegativePair).
template <typename T, typename Y, typename Weight>
std::array<CoefficientPair<T>, 3> EliminatedCoefficients(
    const std::vector<reflectance::LightFactors<T>>& factors, int channels, const double* fixed_ks,
    Y y, Weight weight, const double* prior_ks = nullptr, double prior_weight = 0,
    double ridge = kKsRidge) {
  T d = T(0), x = T(0), s = T(0);
  std::array<T, 3> a = {T(0), T(0), T(0)}, b = {T(0), T(0), T(0)};
  for (std::size_t j = 0; j < factors.size(); ++j) {
    const double w = weight(j);
    if (w == 0) continue;
    const T wd = w * factors[j].diffuse, ws = w * factors[j].specular;
    d += wd * factors[j].diffuse;
    x += wd * factors[j].specular;
    s += ws * factors[j].specular;
    for (int c = 0; c < channels; ++c) {
      a[c] += wd * y(j, c);
      b[c] += ws * y(j, c);
    }
  }
  std::array<CoefficientPair<T>, 3> out;
  if (!(d > T(1e-12))) return out;
  for (int c = 0; c < channels; ++c) {
    if (fixed_ks) {
      out[c].ks = T(fixed_ks[c]);
      out[c].kd = (a[c] - fixed_ks[c] * x) / d;
      if (out[c].kd < T(0)) out[c].kd = T(0);
    } else {
      out[c] = NonNegativePair(d, x, s, a[c], b[c], prior_ks ? prior_weight : 0.0,
                               prior_ks ? prior_ks[c] : 0.0, ridge);
    }
  }
  return out;
}

// Shadows are censored observations. A cast shadow, or a light the pixel sees only in part,
// makes an observation darker than the model predicts by an amount that says nothing about the
// normal: all it says is "less light arrived". So a residual r = y − model is charged
//   ρ(r) = max(r, −t)²,
// the squared error above −t and the constant t² below it: a fit is never pulled to explain
// darkness, yet an observation brighter than predicted (where the model's highlight or diffuse
// term falls short) keeps its full weight, which is what rejects a normal that predicts a shadow
// where the pixel is lit. t = shadow_threshold × the pixel's brightness (BrightnessScale).
inline double CensoredCost(double r, double t) {
  const double c = std::max(r, -t);
  return c * c;
}

// The weight of an observation in the iteratively reweighted fit of ρ: 1 where the residual is
// above −t, 0 where it is censored (a truncated quadratic's reweighting).
inline double CensoredWeight(double r, double t) { return r >= -t ? 1.0 : 0.0; }

// A pixel's brightness for the censoring threshold: the mean of its brightest tenth of usable
// observations (at least one), so it follows the pixel's lit level however many of its images
// are shadowed. `values` is modified (partially sorted).
inline double BrightnessScale(std::vector<double>& values) {
  if (values.empty()) return 1e-6;
  const std::size_t n = std::max<std::size_t>(1, values.size() / 10);
  std::nth_element(values.begin(), values.begin() + (n - 1), values.end(), std::greater<double>());
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) sum += values[i];
  return std::max(sum / n, 1e-6);
}

enum class PixelStatus { kSolved, kDark, kUnderdetermined };

// One pixel's answer, as it passes from Woodham to the search and the local fit.
struct PixelSolution {
  PixelStatus status = PixelStatus::kSolved;
  Vec3d normal = Vec3d(0, 0, 1);
  Vec3d albedo = Vec3d::Zero();
  Vec3d specular = Vec3d::Zero();  // this pixel's ks (RGB)
  double residual = -1;
  // The censored cost of the luminance residuals at the normal (Σ_j ρ(r_j), CensoredCost): what
  // tells two local fits of one pixel apart.
  double cost = INFINITY;
  int iterations = 0;
};

}  // namespace iphong::solve::internal
