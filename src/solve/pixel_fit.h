// The local fit of one pixel's normal: Levenberg–Marquardt on the shared Phong model
// (reflectance/phong.h) with ceres::Jet autodiff, from the global search's winner (search.h).
// The unknowns are 2: the normal on a tangent-plane chart around the start (re-centred when the
// fit strays from it, so the chart never degenerates). The linear coefficients — kd and, unless
// known, ks of each channel, both ≥ 0 — are eliminated in closed form (variable projection,
// internal::EliminatedCoefficients), so their dependence on the normal enters the Jacobian.
// Shadows are censored (internal::CensoredCost): each round refits with the observations the
// last one found censored left out, until the normal stops moving. Saturated observations are
// not used. Observations are y_j = (I_j + c − Ia⊙ka)/E_j, c the code offset on nonzero channels;
// camera frame, V = (0, 0, 1).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "solve/internal.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

// Each observation's weight in the fit by the cosine N·L at which its light strikes the normal
// at the fit's current point, and the object's measured misfit there subtracted from it
// (shading_weights.h estimates both). Empty: every observation alike, nothing subtracted.
struct ShadingWeights {
  std::vector<double> upper;   // each band's upper edge in N·L, ascending (the last is ignored)
  std::vector<double> weight;  // each band's weight, in (0, 1]
  // Each band's offset in units of the pixel's brightness: the model predicts observation j as
  // kd·d_j + ks·s_j + offset(d_j)·brightness (per channel, its share of the brightness). Empty: 0.
  std::vector<double> offset;
  bool empty() const { return upper.empty(); }
  // The first band whose upper edge lies above n_dot_l; the last beyond every edge. The edges
  // ascend, so that is the count of edges at or below it: no data-dependent branch in the fit's
  // inner loop.
  std::size_t Band(double n_dot_l) const {
    std::size_t b = 0;
    for (std::size_t e = 0; e + 1 < upper.size(); ++e) b += !(n_dot_l < upper[e]);
    return b;
  }
  double At(double n_dot_l) const { return weight.empty() ? 1.0 : weight[Band(n_dot_l)]; }
  double OffsetAt(double n_dot_l) const { return offset.empty() ? 0.0 : offset[Band(n_dot_l)]; }
  // "" or what is wrong: sizes differ, edges not ascending, a weight outside (0, 1], an offset
  // not finite or beyond ±1.
  std::string Validate() const;
};

struct PixelFitSettings {
  reflectance::ModelOptions model;  // lobe (kLambert: no specular term)
  double shininess = 1;
  std::optional<Vec3d> known_ks;  // known coefficients; otherwise ks is free per pixel
  // Free ks: the object's typical ks (SharedSpecular) each pixel's is pulled toward, with a weight
  // of `ks_prior_weight` observations of the lobe's peak.
  std::optional<Vec3d> ks_prior;
  double ks_prior_weight = 1;
  Vec3d ambient_term = Vec3d::Zero();  // Ia ⊙ ka
  // Added to every nonzero channel of an observation before anything else: half a code step
  // when the images were truncated to integer codes (NormalOptions::code_offset).
  double code_offset = 0;
  double saturation = 0.995;      // a channel at or above: unused (PixelSaturation)
  double shadow_threshold = 0.1;  // t as a fraction of the pixel's brightness
  int rounds = 4;                 // reweighting rounds
  int max_iterations = 10;        // per round
  bool color_residuals = true;    // 3 channels, or their luminance (faster)
  // ks's pull toward 0 (internal::kKsRidge), a regularizer of the normal where no light shows
  // the lobe; 0 for the model's own misfit (near/near.h compares surfaces by it).
  double ks_ridge = internal::kKsRidge;
  // Censor observations brighter than the model by more than t too (ρ(r) = min(r², t²)): a
  // Lambertian fit that leaves highlights out as it leaves shadows, for placing a surface
  // before the object's lobe is known (near/near.h).
  bool censor_bright = false;
  // Multiplies each uncensored observation's weight, re-read at every censoring round.
  ShadingWeights shading_weights;
};

class PixelFitter {
 public:
  PixelFitter(const PhotometricData& data, const PixelFitSettings& settings);
  ~PixelFitter();
  PixelFitter(const PixelFitter&) = delete;
  PixelFitter& operator=(const PixelFitter&) = delete;

  // Reads pixel p's observations; false when fewer than 3 are usable or when every one is dark
  // (dark() tells which): nothing to fit.
  bool Prepare(std::size_t p);
  bool dark() const;
  // After Prepare: the luminance observations, their usability (0/1), the pixel's brightness
  // (internal::BrightnessScale of its usable luminances) and the censoring threshold t (a
  // fraction of it), for the search.
  const double* luminance() const;
  const double* usable() const;
  double brightness() const;
  double threshold() const;

  // Refines s.normal (unit, the start) in place and sets the albedo, ks, residual (RMS of the
  // usable observations against the model, in image units) and iterations. With `lights` (K
  // weights, 0 or 1) only the lights where it is 1 are fitted: a cross-validation fold's
  // training lights.
  void Fit(internal::PixelSolution& s, const double* lights = nullptr);
  // After Fit: the luminance the fitted model predicts for light j (any light, fitted or not),
  // in the units of luminance().
  double Predicted(int j) const;
  // After Fit: light j's diffuse factor (N·L, 0 when it does not reach the normal).
  double Diffuse(int j) const;
  // After Fit: its censored cost in image units, Σ_j ρ(I_j − E_j·model_j, t)/t² over the
  // unsaturated observations (luminance; t = shadow_threshold × the pixel's recorded
  // brightness), a light that sends the point nothing predicting dark: the images' own misfit,
  // comparable between different lights for the same pixel (near lights at different distances
  // weigh the observations y_j = I_j/E_j differently). With `lights` (K weights, 0 or 1) only
  // those where it is 1.
  double ImageCost(const double* lights = nullptr) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace iphong::solve
