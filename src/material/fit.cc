// FitMaterial: the censored profile fit of each model (linear.cc), Ceres's refinement and
// covariance, and the choice by held-out lights.
#include "material/fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "material/internal.h"
#include "reflectance/material.h"
#include "solve/internal.h"

namespace iphong::material {

using internal::Coefficients;
using internal::Sample;
using reflectance::Lobe;

std::string MaterialFitOptions::Validate() const {
  if (models.empty()) return "no model to fit";
  // The foil centred on the normal is the normal solver's test of a lobe, not a material.
  for (const Lobe m : models) {
    if (m == Lobe::kNormalCentred) return "models must be lambert, phong or blinn-phong";
  }
  if (!(saturation > 0)) return "saturation must be > 0";
  if (!(shadow_threshold > 0 && shadow_threshold < 1)) return "shadow threshold must be in (0, 1)";
  if (folds < 2) return "folds must be at least 2";
  if (max_pixels < 1) return "max_pixels must be at least 1";
  return "";
}

int MinimumLights(Lobe lobe) { return lobe == Lobe::kLambert ? 2 : 4; }

std::string CheckLightCount(int lights, const MaterialFitOptions& options) {
  if (options.models.empty()) return "no model to fit";
  const int k = lights;
  Lobe neediest = options.models.front();
  for (Lobe m : options.models) {
    if (MinimumLights(m) > MinimumLights(neediest)) neediest = m;
  }
  if (k < MinimumLights(neediest)) {
    return std::to_string(k) + " light(s): the " + reflectance::LobeName(neediest) +
           " model needs at least " + std::to_string(MinimumLights(neediest));
  }
  const int folds = std::min(options.folds, k);
  // Interleaved folds: light j in fold j mod F, so each training set spans the light positions
  // the capture has (lights are usually listed ring by ring or in a raster).
  const int smallest_training = k - (k + folds - 1) / folds;
  if (options.models.size() > 1 && smallest_training < MinimumLights(neediest)) {
    const int needed = MinimumLights(neediest) * folds / (folds - 1) + 1;
    return std::to_string(k) + " light(s): choosing between models with " + std::to_string(folds) +
           " folds needs at least " + std::to_string(needed) + " (or name one model)";
  }
  return "";
}

namespace {

using Clock = std::chrono::steady_clock;
double SecondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// The censored least-squares fit of one model: the profile fit on every allowed observation,
// then twice: censor what it predicts as shadow, fit again.
Coefficients CensoredFit(const Sample& s, Lobe lobe, const std::vector<unsigned char>& allowed,
                         std::vector<unsigned char>* used, std::size_t* censored) {
  Coefficients c = internal::ProfileFit(s, lobe, allowed);
  for (int round = 0; round < 2; ++round) {
    *censored = internal::Censor(s, lobe, c, allowed, used);
    c = internal::ProfileFit(s, lobe, *used, c.shininess);
  }
  return c;
}

// The held-out cost of the observations of one fold: censored squared residuals per pixel.
void ScoreFold(const Sample& s, Lobe lobe, const Coefficients& c,
               const std::vector<unsigned char>& test, std::vector<double>* cost,
               std::vector<std::size_t>* count) {
  for (std::size_t p = 0; p < s.size(); ++p) {
    for (int j = 0; j < s.lights; ++j) {
      const std::size_t i = p * s.lights + j;
      if (!test[i]) continue;
      const Vec3d predicted = internal::Predict(s, lobe, c, p, j);
      const float* y = s.y(p, j);
      for (int ch = 0; ch < 3; ++ch) {
        (*cost)[p] += solve::internal::CensoredCost(y[ch] - predicted[ch], s.threshold[p][ch]);
      }
      (*count)[p] += 3;
    }
  }
}

}  // namespace

MaterialFit FitMaterial(const solve::PhotometricData& data, const std::vector<Vec3d>& normals_cam,
                        const MaterialFitOptions& options) {
  const auto start = Clock::now();
  if (std::string m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (std::string m = data.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (normals_cam.size() != data.pixel_count()) {
    throw std::invalid_argument(std::to_string(normals_cam.size()) + " normals for " +
                                std::to_string(data.pixel_count()) + " pixels");
  }
  if (options.albedo == AlbedoMode::kPerRegion && options.region.size() != data.pixel_count()) {
    throw std::invalid_argument("region labels: " + std::to_string(options.region.size()) +
                                " for " + std::to_string(data.pixel_count()) + " pixels");
  }
  std::vector<Vec3d> normals(normals_cam.size(), Vec3d::Zero());
  std::size_t given = 0, back_facing = 0;
  for (std::size_t p = 0; p < normals_cam.size(); ++p) {
    const Vec3d& n = normals_cam[p];
    if (!n.allFinite()) {
      const int px = data.pixels[p];
      throw std::invalid_argument("the normal at pixel (" + std::to_string(px % data.width) + ", " +
                                  std::to_string(px / data.width) + ") is not finite");
    }
    if (n.squaredNorm() == 0) continue;  // no normal: left out
    normals[p] = n.normalized();
    ++given;
    back_facing += !(n.z() > 0);
  }
  // A visible surface faces the camera (nz > 0); a few pixels at the rim may not, most of them
  // mean a normal map in another frame, and the fit would explain the photos with ambient alone.
  if (2 * back_facing > given) {
    throw std::invalid_argument(std::to_string(back_facing) + " of " + std::to_string(given) +
                                " normals face away from the camera (nz <= 0): a normal map in "
                                "another frame (z into the scene?)");
  }
  const int k = data.images;
  if (std::string m = CheckLightCount(k, options); !m.empty()) throw std::invalid_argument(m);
  // Photos that are black wherever there is a normal hold nothing to fit: every model explains
  // them with zero coefficients (it came out as ka 0, ks 0, n 1 behind a warning).
  {
    bool lit = false;
    for (std::size_t p = 0; p < normals.size() && !lit; ++p) {
      if (normals[p].squaredNorm() == 0) continue;
      const float* v = data.pixel(p);
      for (int i = 0; i < 3 * k && !lit; ++i) lit = v[i] > 0;
    }
    if (!lit && given > 0) {  // none at all is the "no pixel" error below
      throw std::invalid_argument(
          "the photos are black (0) wherever the object is: nothing to "
          "fit (under-exposed, or the wrong folder?)");
    }
  }
  const bool choose = options.models.size() > 1;
  const int folds = std::min(options.folds, k);
  MaterialFit result;
  std::vector<std::size_t> with_normal;
  std::vector<int> group_of;
  const Sample s = internal::BuildSample(data, normals, options, &with_normal, &group_of);
  result.pixels = with_normal.size();
  result.fitted_pixels = s.size();
  for (unsigned char u : s.usable) result.saturated += !u;
  // With every lit observation at or above the saturation level only the black ones are left:
  // every model explained them with zero coefficients at a held-out error of 0 (a NaN noise
  // ratio), and that material was written.
  {
    bool lit_usable = false;
    for (std::size_t p = 0; p < s.size() && !lit_usable; ++p) {
      for (int j = 0; j < s.lights && !lit_usable; ++j) {
        const float* y = s.y(p, j);
        lit_usable = s.usable[p * s.lights + j] && (y[0] > 0 || y[1] > 0 || y[2] > 0);
      }
    }
    if (!lit_usable && s.size() > 0) {
      char level[32];
      std::snprintf(level, sizeof level, "%.3g", options.saturation);
      throw std::invalid_argument(
          std::string("every lit observation is at or above the saturation level ") + level +
          ": nothing to fit (a saturation below the photos' values, or photos clipped white?)");
    }
  }
  result.fold.resize(k);
  for (int j = 0; j < k; ++j) result.fold[j] = j % folds;

  const bool eliminate = options.albedo == AlbedoMode::kPerPixel;
  const double fits = static_cast<double>(options.models.size()) * (choose ? folds + 1 : 1);
  int fits_done = 0;
  auto fitted = [&] {
    if (options.progress) options.progress(++fits_done / fits);
  };
  std::vector<Coefficients> coefficients;
  std::vector<std::size_t> censored(options.models.size(), 0);
  std::vector<std::vector<unsigned char>> used(options.models.size());
  for (std::size_t m = 0; m < options.models.size(); ++m) {
    Coefficients c = CensoredFit(s, options.models[m], s.usable, &used[m], &censored[m]);
    result.models.push_back(
        internal::Refine(s, options.models[m], eliminate, used[m], options.threads, &c));
    result.summary.iterations += result.models.back().iterations;
    fitted();
    coefficients.push_back(std::move(c));
  }

  // Held-out prediction: every model fitted without fold f predicts fold f's observations.
  const auto choice_start = Clock::now();
  const std::size_t models = options.models.size();
  std::vector<std::vector<double>> cost(models, std::vector<double>(s.size(), 0));
  std::vector<std::vector<std::size_t>> count(models, std::vector<std::size_t>(s.size(), 0));
  if (choose) {
    for (int f = 0; f < folds; ++f) {
      std::vector<unsigned char> train = s.usable, test = s.usable;
      for (std::size_t p = 0; p < s.size(); ++p) {
        for (int j = 0; j < k; ++j) {
          const std::size_t i = p * k + j;
          (result.fold[j] == f ? train : test)[i] = 0;
        }
      }
      std::vector<Coefficients> fold_fit(models);
      for (std::size_t m = 0; m < models; ++m) {
        std::vector<unsigned char> fold_used;
        std::size_t fold_censored = 0;
        fold_fit[m] = CensoredFit(s, options.models[m], train, &fold_used, &fold_censored);
        fitted();
      }
      // A pixel counts only where every model knows its albedo, so the scores are paired.
      std::vector<unsigned char> scored_test = test;
      for (std::size_t p = 0; p < s.size(); ++p) {
        bool known = true;
        for (const Coefficients& c : fold_fit) known = known && c.kd_known[s.group[p]];
        if (!known) std::fill_n(scored_test.begin() + p * k, k, 0);
      }
      for (std::size_t m = 0; m < models; ++m) {
        ScoreFold(s, options.models[m], fold_fit[m], scored_test, &cost[m], &count[m]);
      }
    }
    double best_sigma = INFINITY;
    for (const ModelFit& fit : result.models) {
      if (std::isfinite(fit.sigma)) best_sigma = std::min(best_sigma, fit.sigma);
    }
    for (std::size_t m = 0; m < models; ++m) {
      double total = 0;
      std::size_t n = 0;
      for (std::size_t p = 0; p < s.size(); ++p) total += cost[m][p], n += count[m][p];
      ModelFit& fit = result.models[m];
      fit.heldout_observations = n;
      fit.heldout_rmse = n > 0 ? std::sqrt(total / n) : NAN;
      fit.heldout_ratio = fit.heldout_rmse / best_sigma;
    }
    // The lowest held-out error wins; a model with a lobe must beat Lambert by more than two
    // standard errors of the paired per-pixel difference and by 1 %, or the simpler one stays.
    int best = 0;
    for (std::size_t m = 1; m < models; ++m) {
      if (result.models[m].heldout_rmse < result.models[best].heldout_rmse) best = m;
    }
    std::ostringstream note;
    note.precision(4);
    const auto lambert = std::find(options.models.begin(), options.models.end(), Lobe::kLambert);
    if (options.models[best] != Lobe::kLambert && lambert != options.models.end()) {
      const std::size_t l = lambert - options.models.begin();
      double sum = 0, sum2 = 0;
      std::size_t n = 0;
      for (std::size_t p = 0; p < s.size(); ++p) {
        if (count[l][p] == 0) continue;
        const double diff = (cost[l][p] - cost[best][p]) / count[l][p];
        sum += diff, sum2 += diff * diff, ++n;
      }
      const double mean = n ? sum / n : 0;
      const double se = n > 1 ? std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1)) : 0;
      note << reflectance::LobeName(options.models[best]) << " predicts held-out lights with RMSE "
           << result.models[best].heldout_rmse << " against Lambert's "
           << result.models[l].heldout_rmse << " (paired difference ";
      if (se > 0) {
        note << mean / se << " standard errors";
      } else {
        note << mean << ", the same at every pixel";
      }
      note << " over " << n << " pixels)";
      // And by 1 % of Lambert's RMSE: four more coefficients for less is not a highlight (on
      // exact Lambertian renders a lobe fits float rounding: 2.903e-8 against 2.904e-8).
      if (!(mean > 2 * se) ||
          !(result.models[best].heldout_rmse < 0.99 * result.models[l].heldout_rmse)) {
        note << ": not significant, Lambert kept";
        best = static_cast<int>(l);
      }
    } else {
      note << reflectance::LobeName(options.models[best]) << " predicts held-out lights best (RMSE "
           << result.models[best].heldout_rmse << ")";
    }
    result.chosen = best;
    result.choice_note = note.str();
  } else {
    result.choice_note = "one model given: " + reflectance::LobeName(options.models[0]);
  }
  result.summary.choice_seconds = SecondsSince(choice_start);

  const Lobe lobe = options.models[result.chosen];
  const Coefficients& chosen = coefficients[result.chosen];
  result.censored = censored[result.chosen];
  if (eliminate) {
    result.albedo = internal::PixelAlbedos(data, normals, with_normal, lobe, chosen, options);
  } else {
    result.albedo.assign(data.pixel_count(), Vec3d::Constant(NAN));
    for (std::size_t p : with_normal) {
      if (chosen.kd_known[group_of[p]]) result.albedo[p] = chosen.kd[group_of[p]];
    }
  }
  // The lobe to show: the chosen model's, or where Lambert won the best-predicting lobe's.
  if (options.models[result.chosen] != Lobe::kLambert) {
    result.lobe_model = result.chosen;
  } else {
    for (std::size_t m = 0; m < models; ++m) {
      if (options.models[m] == Lobe::kLambert) continue;
      if (result.lobe_model < 0 ||
          result.models[m].heldout_rmse < result.models[result.lobe_model].heldout_rmse) {
        result.lobe_model = static_cast<int>(m);
      }
    }
  }
  if (result.lobe_model >= 0) {
    result.lobe = internal::LobeBins(s, coefficients[result.lobe_model],
                                     options.models[result.lobe_model], used[result.lobe_model]);
  }
  result.summary.success = true;
  result.summary.seconds = SecondsSince(start);
  result.summary.message = result.choice_note;
  return result;
}

}  // namespace iphong::material
