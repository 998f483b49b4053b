// Normal recovery: per-pixel unit normals and RGB albedo from K ≥ 3 images under known lights,
// by inverting the shared Phong model (reflectance/phong.h) with Ceres.
//
// 1. Woodham's Lambertian least squares per pixel on the luminance of I_j / E_j, using the
//    observations left after dropping the darkest and brightest fractions (shadows, highlights).
//    This is also the `lambert` result.
// 2. A per-pixel nonlinear fit of the Phong (or Blinn-Phong) model: Levenberg–Marquardt with
//    ceres::Jet autodiff through the shared model. The unknowns are 2: the normal on a
//    tangent-plane chart around the Woodham estimate (re-centred when the fit strays from it, so
//    the chart never degenerates). The RGB albedo is linear in the residuals and eliminated in
//    closed form (variable projection). The model runs once per light and trial point; the
//    normal equations, robust weights, albedo and residual are all drawn from that run. Cauchy
//    weights (iteratively reweighted, one per image) absorb cast shadows and interreflections;
//    attached shadows are in the model (N·L ≤ 0 gives the ambient value); saturated observations
//    are dropped. Optionally (restart_residual), where the residual stays large, a second start
//    from Woodham on the darker observations; the lower robust cost wins.
// 3. Without known coefficients, ks (RGB), the shininess and the ambient term Ia⊙ka (RGB) are
//    estimated jointly with the normals: rounds of a
//    global Ceres fit over a sample of pixels (normals fixed, albedo eliminated) alternate with
//    the per-pixel fits. When no highlight is seen they are reported as not identifiable. They
//    are shared by the object, or estimated per cluster of the albedo (specular_clusters), and
//    their strength may vary from pixel to pixel (varying_specular).
// Frame: SPEC.md's camera frame, orthographic view V = (0, 0, 1).
#pragma once

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "reflectance/material.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

struct NormalOptions {
  reflectance::Lobe model = reflectance::Lobe::kPhong;  // kLambert: Woodham only
  // Woodham: fractions of each pixel's observations dropped, darkest and brightest first.
  double discard_dark = 0.3;
  double discard_bright = 0.1;
  // Observations with a channel at or above this value are treated as saturated and unused.
  double saturation = 0.995;
  // Cauchy scale relative to the pixel's mean observation.
  double robust_scale = 0.15;
  int irls_rounds = 4;
  // A fit whose RMS residual exceeds this fraction of the pixel's mean value is restarted from
  // Woodham on the darker observations (guards against local minima near highlights); the lower
  // robust cost wins. Off by default: on renders it gains little (0.014° → 1e-5° in the test),
  // and on DiLiGenT the robust cost picked the worse normal where shadows and interreflections
  // dominate (cat 5.89° without, 5.95° at 0.02 and 0.08; pot1 crop 8.18° vs 8.37°), at twice
  // the time (43% of cat's pixels restarted at 0.02).
  double restart_residual = std::numeric_limits<double>::infinity();
  // Fit the normal to all three channels (each with its own albedo). Off: to their luminance,
  // exact under the model and about twice as fast, a little less accurate on real photos.
  bool color_residuals = true;
  int max_iterations = 10;  // per pixel and round

  // Known coefficients (material.json). Otherwise ks and shininess are estimated.
  bool material_known = false;
  Vec3d ambient_term = Vec3d::Zero();  // Ia ⊙ ka, subtracted from every image
  Vec3d ks = Vec3d::Zero();
  double shininess = 1;
  int specular_rounds = 2;
  int specular_sample = 500;  // pixels in the global fit (per cluster)
  // Objects of several materials: ks, shininess and the ambient term per cluster of the
  // (Woodham) albedo, by k-means on its chromaticity and brightness. 1 = shared by the object.
  int specular_clusters = 1;
  // Estimated coefficients only: each pixel's ks is its cluster's times a scale σ ≥ 0, eliminated
  // in closed form with the albedo, for gloss that varies over the surface (glaze, wear, paint).
  // Known coefficients (material.json) are used as given.
  bool varying_specular = true;
  // The pull of σ toward 1, in observations of the lobe's peak. 1 suits DiLiGenT's 96 lights;
  // with few lights or rare highlights it shrinks σ noticeably (a weaker pull follows gloss
  // better where every pixel sees a highlight).
  double specular_prior = 1;
  // A known uniform albedo kd: what one or two images need (RecoverNormals).
  std::optional<Vec3d> known_albedo;

  int threads = 0;
  // Called with the fraction done (0..1) from worker threads; must be thread-safe.
  std::function<void(double)> progress;

  std::string Validate() const;
};

struct NormalSummary {
  bool success = false;
  std::string message;
  double init_seconds = 0;      // Woodham
  double specular_seconds = 0;  // global fits of ks and shininess
  double solve_seconds = 0;     // per-pixel nonlinear fits
  long long iterations = 0;     // per-pixel solver iterations, summed
  std::size_t pixels = 0;
  std::size_t dark_pixels = 0;             // dark in every image: no normal (flagged)
  std::size_t underdetermined_pixels = 0;  // fewer than 3 usable lights (flagged)
};

// The specular coefficients of one albedo cluster (of the whole object when there is one).
struct SpecularCluster {
  Vec3d albedo_center = Vec3d::Zero();  // mean Woodham albedo of its pixels
  std::size_t pixels = 0;
  Vec3d ks = Vec3d::Zero();
  double shininess = 1;
  Vec3d ambient_term = Vec3d::Zero();
  bool estimated = false;  // false: known (material.json) or not identifiable
  bool identifiable = true;
  std::string note;
};

struct NormalResult {
  ImageF normals;   // 3 channels, unit xyz in the camera frame; 0 outside the mask
  ImageF albedo;    // 3 channels, kd
  ImageF specular;  // 3 channels, each pixel's ks (its cluster's, times σ); empty for lambert
  ImageF residual;  // 1 channel: RMS model residual per pixel; −1 where no normal was found
  reflectance::Lobe model = reflectance::Lobe::kPhong;
  Vec3d ks = Vec3d::Zero();
  double shininess = 1;
  Vec3d ambient_term = Vec3d::Zero();  // Ia ⊙ ka, known or estimated
  bool material_estimated = false;
  bool specular_identifiable = true;
  std::string specular_note;
  // One per cluster; ks, shininess and ambient_term above are the largest cluster's.
  std::vector<SpecularCluster> clusters;
  ImageF cluster_map;  // 1 channel: the cluster of each pixel, −1 outside (clusters > 1 only)
  // One or two images only: the angle the data alone leaves open per pixel (few_images.h).
  ImageF ambiguity_deg;
  NormalSummary summary;
};

// Throws std::invalid_argument for invalid data or options (one-line message).
NormalResult EstimateNormals(const PhotometricData& data, const NormalOptions& options);

// Any number of images: EstimateNormals for three or more; for one or two the global solver with
// priors (EstimateNormalsFewImages), which needs the coefficients known (material_known) and
// `known_albedo`; its albedo is then that kd inside the mask and ambiguity_deg is set.
NormalResult RecoverNormals(const PhotometricData& data, const NormalOptions& options);

}  // namespace iphong::solve
