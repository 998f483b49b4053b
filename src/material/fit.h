// Material fitting: the Phong coefficients of an object whose normals are known (ground truth,
// an `iphong normals` result, or a sphere fitted to its mask), from its images under K known
// lights, with standard errors, and the model chosen by how well it predicts held-out lights.
//
// Model (reflectance/phong.h, the one shared spelling), per pixel p, light j and channel c:
//   y_pjc = a_c + E_jc · (kd_gc · d_pj + ks_c · s_pj(n)),   d = max(N·L, 0), s = the lobe,
// with a = Ia⊙ka (only the product is observable), kd per albedo group g (every pixel its own,
// one for the object, or one per region), ks RGB and the shininess n shared by the object.
// Frame: SPEC.md's camera frame, orthographic view V = (0, 0, 1).
//
// The fit, per model:
// 1. For a fixed n the model is linear in (a, kd, ks): the albedos are eliminated in closed form
//    (a 2×2 system per channel), so the profile cost on a grid n = 2^(k/2) over [1, 4096],
//    refined by parabolic interpolation, finds the global optimum of the shininess: no start can
//    trap it.
// 2. Shadows are censored as in normal recovery (solve/internal.h): an observation darker than
//    the model by more than shadow_threshold × the pixel's brightness in some channel is left
//    out (a cast shadow says only "less light arrived"); saturated observations are never used.
// 3. Ceres refines (a, ks, log n) jointly with the albedos eliminated inside the residual
//    (variable projection; exact derivatives through the elimination) or, for one or a few
//    albedos, as parameters. The loss is the censored squares of 2. (brighter observations,
//    interreflections included, keep their weight: they are what tells a lobe from none).
// 4. Standard errors σ̂² (JᵀJ)⁻¹ from Ceres's Jacobians at the optimum, σ̂² = RSS /
//    (observations − parameters) where the eliminated albedos count as parameters: the marginal
//    covariance of the shared coefficients (the Schur complement of the full problem), what
//    ceres::Covariance gives, without its SVD of the whole Jacobian. Beside them, robust (sandwich)
//    standard errors with the pixels as independent clusters, which stay honest where the model
//    does not fit to the noise: on real photos they are the ones to quote.
// Model choice: the lights are split into interleaved folds (light j in fold j mod F); each
// model is fitted without a fold and predicts its images; the held-out RMSE (censored like the
// fit, so cast shadows do not decide) chooses. A specular model must beat Lambert by more than
// two standard errors of the paired per-pixel difference, and by 1 % of its RMSE, to be chosen.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/types.h"
#include "reflectance/phong.h"
#include "solve/photometric_data.h"

namespace iphong::material {

enum class AlbedoMode {
  kPerPixel,   // every pixel its own kd (the usual: texture, paint)
  kUniform,    // one kd for the object (a sphere of one material)
  kPerRegion,  // one kd per region label
};

struct MaterialFitOptions {
  // The candidate models; the first is the fallback when none can be scored.
  std::vector<reflectance::Lobe> models = {reflectance::Lobe::kLambert, reflectance::Lobe::kPhong,
                                           reflectance::Lobe::kBlinnPhong};
  AlbedoMode albedo = AlbedoMode::kPerPixel;
  // kPerRegion: a label ≥ 0 per pixel of the observations (data.pixels order); −1 = left out.
  std::vector<int> region;
  double saturation = 0.995;      // a channel at or above: unused (solve::PixelSaturation)
  double shadow_threshold = 0.1;  // censoring, as solve::NormalOptions::shadow_threshold
  int folds = 2;                  // model choice: interleaved folds of the lights (≥ 2)
  // Pixels the shared coefficients are fitted to: an even sample (every k-th), kd then solved
  // for all. A sharp highlight covers few pixels per light, so a sparse sample misses part of
  // it: DiLiGenT ball's ks was 0.79 ± 0.05 (robust s.e.) from every 4th pixel, 0.94 ± 0.03
  // from all 15 791. 20 000 keeps every pixel of the DiLiGenT objects' masks but the largest.
  int max_pixels = 20000;
  int threads = 0;
  // Called with the fraction of the fits done (0..1), from the calling thread.
  std::function<void(double)> progress;

  std::string Validate() const;
};

// The fewest lights a model needs with the normals known: Lambert 2 (kd and the ambient term
// apart), Phong and Blinn-Phong 4 (ks and the shininess besides). The model choice needs one
// fold more than this in every training set.
int MinimumLights(reflectance::Lobe lobe);

// "" when `lights` are enough for the options' models (and their choice), else the one-line
// reason with the number needed.
std::string CheckLightCount(int lights, const MaterialFitOptions& options);

// One model fitted to all the lights, and scored on held-out ones.
struct ModelFit {
  reflectance::Lobe lobe = reflectance::Lobe::kLambert;
  Vec3d ambient_term = Vec3d::Zero();  // Ia⊙ka
  Vec3d ks = Vec3d::Zero();
  double shininess = 0;   // 0 for Lambert
  std::vector<Vec3d> kd;  // per albedo group (kPerPixel: per fitted pixel)
  // Standard errors (NaN where the covariance is rank deficient: e.g. n when ks is 0).
  Vec3d ambient_se = Vec3d::Constant(NAN);
  Vec3d ks_se = Vec3d::Constant(NAN);
  double shininess_se = NAN;
  Vec3d ks_shininess_correlation = Vec3d::Constant(NAN);  // per channel
  std::vector<Vec3d> kd_se;  // kUniform / kPerRegion: per group; kPerPixel: empty
  // Robust (sandwich) standard errors, pixels as independent clusters: equal to the above where
  // the model is right and the noise independent, larger where the model misfits (real photos).
  Vec3d ambient_robust_se = Vec3d::Constant(NAN);
  Vec3d ks_robust_se = Vec3d::Constant(NAN);
  double shininess_robust_se = NAN;
  bool covariance_ok = false;

  double rss = 0;                // Σ r² over the observations used
  double sigma = 0;              // σ̂ = sqrt(rss / (observations − parameters))
  std::size_t observations = 0;  // scalar observations (3 per light and pixel) used
  std::size_t parameters = 0;    // the shared ones plus every albedo
  double bic = 0;                // observations · ln(rss / observations) + parameters · ln(obs.)
  int iterations = 0;            // Ceres iterations of the refinement
  bool converged = false;

  double heldout_rmse = NAN;   // predicting held-out lights (censored), image units
  double heldout_ratio = NAN;  // heldout_rmse / the best model's σ̂: ≈ 1 is as good as noise
  std::size_t heldout_observations = 0;
};

// The specular lobe as the data show it: per bin of the lobe's angle (R to V for Phong, N to H
// for Blinn-Phong), the mean of (observation − ambient − diffuse) / (E·ks) in luminance.
struct LobeBin {
  double angle_deg = 0;  // bin centre
  double mean = 0;
  double standard_error = 0;
  std::size_t count = 0;
};

struct MaterialFitSummary {
  bool success = false;
  std::string message;
  double seconds = 0;
  double choice_seconds = 0;  // the held-out fits
  int iterations = 0;         // Ceres iterations, all fits
};

struct MaterialFit {
  std::vector<ModelFit> models;  // in options.models' order
  int chosen = 0;                // index into models
  std::vector<int> fold;         // each light's fold
  std::string choice_note;       // why the chosen model won
  // The chosen model's kd for every pixel of the observations with a normal (kPerPixel), or
  // its group's; NaN where no usable observation lit the pixel.
  std::vector<Vec3d> albedo;
  // The lobe of the chosen model or, where Lambert won, of the best-predicting model with a lobe
  // (the data then show no highlight); empty when no model has one. lobe_model indexes models.
  std::vector<LobeBin> lobe;
  int lobe_model = -1;
  std::size_t pixels = 0;         // pixels with a normal
  std::size_t fitted_pixels = 0;  // of them, in the fit's sample
  std::size_t saturated = 0;      // observations left out as saturated (sample)
  std::size_t censored = 0;       // and as shadowed, by the chosen model's fit
  MaterialFitSummary summary;

  const ModelFit& best() const { return models[chosen]; }
};

// `normals_cam`: one unit normal per pixel of `data` (data.pixels order); a zero vector marks
// a pixel without one. Throws std::invalid_argument (one line) for invalid options, sizes that
// differ, non-finite normals, no usable pixel, or too few lights for the models (naming how
// many are needed).
MaterialFit FitMaterial(const solve::PhotometricData& data, const std::vector<Vec3d>& normals_cam,
                        const MaterialFitOptions& options);

// The model's image under light j for the pixels of `data`: a + E_j (kd d + ks s), with
// `albedo` per pixel (FitMaterial's). Pixels without normal or albedo are 0. Width×height×3.
ImageF PredictImage(const solve::PhotometricData& data, const std::vector<Vec3d>& normals_cam,
                    const ModelFit& model, const std::vector<Vec3d>& albedo, int light);

// The observed image j of `data` (its masked pixels; 0 elsewhere). Width×height×3.
ImageF ObservedImage(const solve::PhotometricData& data, int light);

}  // namespace iphong::material
