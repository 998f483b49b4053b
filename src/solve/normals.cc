#include "solve/normals.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "core/parallel.h"
#include "core/timing.h"
#include "solve/assemble.h"
#include "solve/few_images.h"
#include "solve/heldout_internal.h"
#include "solve/internal.h"
#include "solve/light_tiles.h"
#include "solve/pixel_fit.h"
#include "solve/search.h"
#include "solve/woodham.h"

namespace iphong::solve {
namespace internal {

WoodhamSettings WoodhamOf(const NormalOptions& o) {
  return {o.discard_dark, o.discard_bright, o.saturation, o.ambient_term};
}

PixelFitSettings FitSettingsOf(const NormalOptions& o) {
  PixelFitSettings s;
  s.model.lobe = o.model;
  s.shininess = o.shininess;
  if (o.material_known) s.known_ks = o.ks;
  s.ambient_term = o.ambient_term;
  s.code_offset = o.code_offset;
  s.saturation = o.saturation;
  s.shadow_threshold = o.shadow_threshold;
  s.rounds = o.irls_rounds;
  s.max_iterations = o.max_iterations;
  s.color_residuals = o.color_residuals;
  s.shading_weights = o.shading_weights;
  return s;
}

PixelFitSettings PlanFitSettings(const NormalPlan& plan) {
  const NormalOptions& o = plan.options;
  PixelFitSettings fit = FitSettingsOf(o);
  if (const ModelCandidate& m = plan.model_choice.chosen;
      !o.material_known && m.ks_prior_weight > 0) {
    fit.ks_prior = m.ks_prior;
    fit.ks_prior_weight = m.ks_prior_weight;
  }
  return fit;
}

void CheckInputs(const PhotometricData& data, const NormalOptions& options) {
  if (auto m = data.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (data.images < 3) {
    throw std::invalid_argument("per-pixel photometric stereo needs at least 3 images, got " +
                                std::to_string(data.images));
  }
}

}  // namespace internal

namespace {

using internal::CheckInputs;
using internal::FitSettingsOf;
using internal::PixelSolution;
using internal::PixelStatus;
using internal::WoodhamOf;

// The per-channel median of the pixels' ks: the object's typical coefficient.
Vec3d MedianKs(const std::vector<Vec3f>& ks) {
  Vec3d out = Vec3d::Zero();
  if (ks.empty()) return out;
  std::vector<double> v(ks.size());
  for (int c = 0; c < 3; ++c) {
    for (std::size_t i = 0; i < ks.size(); ++i) v[i] = ks[i][c];
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    out[c] = v[v.size() / 2];
  }
  return out;
}

}  // namespace

std::string NormalOptions::Validate() const {
  if (!(discard_dark >= 0 && discard_bright >= 0 && discard_dark + discard_bright < 1)) {
    return "discard fractions must be >= 0 and sum to less than 1";
  }
  if (!(saturation > 0)) return "saturation level must be > 0";
  if (!(shadow_threshold > 0) || !std::isfinite(shadow_threshold)) {
    return "shadow threshold must be > 0";
  }
  if (irls_rounds < 1 || max_iterations < 1) return "irls rounds and iterations must be >= 1";
  if (search_candidates < 16 || search_candidates > 100000) {
    return "search candidates must be in 16..100000";
  }
  if (model_sample < 1) return "model sample must be >= 1";
  if (plan_sample < 1) return "plan sample must be >= 1";
  if (!ambient_term.allFinite() || (ambient_term.array() < 0).any()) {
    return "ambient term must be finite and >= 0";
  }
  if (!(code_offset >= 0 && code_offset < 0.5)) return "code offset must be in [0, 0.5)";
  if (!ks.allFinite() || (ks.array() < 0).any() || !std::isfinite(shininess) || shininess < 0) {
    return "ks and shininess must be finite and >= 0";
  }
  if (auto m = shading_weights.Validate(); !m.empty()) return m;
  return "";
}

void internal::AssembleNormals(const PhotometricData& data, const NormalOptions& o,
                               const std::vector<PixelSolution>& solutions,
                               const std::vector<signed char>& won, bool per_pixel_map,
                               NormalResult& result) {
  const std::size_t pixels = data.pixel_count();
  result.model = o.model;
  result.shininess = o.shininess;
  result.ambient_term = o.ambient_term;
  result.code_offset = o.code_offset;
  const bool specular = o.model != reflectance::Lobe::kLambert;
  if (per_pixel_map) {
    result.model_map = ImageF(data.width, data.height, 1, -1.0f);
    for (std::size_t i = 0; i < pixels; ++i) {
      if (solutions[i].status == PixelStatus::kSolved) {
        result.model_map.pixels[static_cast<std::size_t>(data.pixels[i])] = won[i];
      }
    }
  }
  result.normals = ImageF(data.width, data.height, 3);
  result.albedo = ImageF(data.width, data.height, 3);
  result.residual = ImageF(data.width, data.height, 1);
  if (specular) result.specular = ImageF(data.width, data.height, 3);
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::size_t p = static_cast<std::size_t>(data.pixels[i]);
    const PixelSolution& s = solutions[i];
    if (s.status == PixelStatus::kDark) ++result.summary.dark_pixels;
    if (s.status == PixelStatus::kUnderdetermined) ++result.summary.underdetermined_pixels;
    const bool ok = s.status == PixelStatus::kSolved && s.normal.allFinite();
    const Vec3d n = ok ? s.normal : Vec3d(0, 0, 1);  // never NaN: flagged in the residual map
    for (int c = 0; c < 3; ++c) {
      result.normals.pixels[3 * p + c] = static_cast<float>(n[c]);
      result.albedo.pixels[3 * p + c] = ok ? static_cast<float>(s.albedo[c]) : 0.0f;
      if (specular && ok) result.specular.pixels[3 * p + c] = static_cast<float>(s.specular[c]);
    }
    result.residual.pixels[p] = ok ? static_cast<float>(s.residual) : -1.0f;
  }
  result.summary.success = true;
  result.summary.message =
      "solved " +
      std::to_string(pixels - result.summary.dark_pixels - result.summary.underdetermined_pixels) +
      " of " + std::to_string(pixels) + " pixels";
}

NormalResult SolveNormalsWithPlan(const PhotometricData& data, const NormalPlan& plan) {
  const NormalOptions& o = plan.options;
  CheckInputs(data, o);
  // A plan can come from elsewhere (Python, a Dask worker): its folds index the lights, and their
  // count sizes the search's tables, so they are checked before anything is read or allocated.
  if (const std::vector<int>& fold = plan.model_choice.fold; !fold.empty()) {
    const int folds = FoldCount(data.images);
    const bool fits =
        static_cast<int>(fold.size()) == data.images &&
        std::all_of(fold.begin(), fold.end(), [&](int f) { return f >= 0 && f < folds; });
    if (!fits) {
      throw std::invalid_argument("plan: fold must give each of the " +
                                  std::to_string(data.images) + " lights a fold in 0.." +
                                  std::to_string(folds - 1) + " (a plan for other lights?)");
    }
  }
  const std::size_t pixels = data.pixel_count();
  std::vector<PixelSolution> solutions(pixels);
  NormalResult result;
  result.summary.pixels = pixels;
  result.summary.model_seconds = plan.model_seconds;
  result.model_choice = plan.model_choice;
  std::vector<signed char> won;  // per_pixel_model: which model each pixel chose (1: specular)
  bool per_pixel_map = false;    // model_map made (on every piece, even one with no pixel)

  if (plan.requested_model == reflectance::Lobe::kLambert) {
    const auto start = Clock::now();
    const Eigen::Matrix3Xd pinv = WoodhamPseudoInverse(data);
    const WoodhamSettings woodham = WoodhamOf(o);
    ParallelFor(0, pixels, 1024, o.threads, [&](std::size_t b, std::size_t e) {
      std::vector<std::pair<double, int>> order;
      order.reserve(data.images);
      PixelLights lights(data);
      for (std::size_t p = b; p < e; ++p)
        solutions[p] = Woodham(data, p, woodham, pinv, order, lights, true);
    });
    result.summary.init_seconds = SecondsSince(start);
  } else {
    const auto start = Clock::now();
    const PixelFitSettings fit = internal::PlanFitSettings(plan);
    // The search runs on luminance: the known ks enters as its luminance.
    const double ks_luminance = internal::Luminance(o.ks);
    reflectance::ModelOptions model;
    model.lobe = o.model;
    // The per-pixel choice between Lambert and the object's model, on the choice's halves.
    const std::vector<int>& fold = plan.model_choice.fold;
    const WoodhamSettings woodham = WoodhamOf(o);
    const bool per_pixel = !o.material_known && o.per_pixel_model &&
                           o.model != reflectance::Lobe::kLambert && !fold.empty();
    PixelFitSettings lambert_fit = fit;
    lambert_fit.model.lobe = reflectance::Lobe::kLambert;
    lambert_fit.ks_prior.reset();
    won.assign(per_pixel ? pixels : 0, -1);
    per_pixel_map = per_pixel;
    // One table per tile of pixels that see the lights alike (one tile for distant lights).
    struct Tables {
      CandidateTable model;
      std::optional<CandidateTable> lambert;
    };
    const std::vector<LightTile> tiles =
        MakeLightTiles(data, TileToleranceDeg(o.model, o.shininess));
    const auto make_tables = [&](std::size_t t) {
      Tables tables{
          CandidateTable(tiles[t].light_directions, model, o.shininess, o.search_candidates, fold),
          std::nullopt};
      if (per_pixel) {
        reflectance::ModelOptions lambert;
        lambert.lobe = reflectance::Lobe::kLambert;
        tables.lambert.emplace(tiles[t].light_directions, lambert, 1.0, o.search_candidates, fold);
      }
      return tables;
    };
    std::atomic<std::size_t> done{0};
    std::atomic<long long> iterations{0};
    ForEachTileChunk(
        tiles, 128, o.threads, make_tables,
        [&](std::size_t tile, const Tables& tables, std::size_t b, std::size_t e) {
          const CandidateTable& table = tables.model;
          PixelFitter fitter(data, fit);
          std::optional<PixelFitter> lambert_fitter;
          std::optional<NormalSearch> lambert_search;
          if (per_pixel) {
            lambert_fitter.emplace(data, lambert_fit);
            lambert_search.emplace(*tables.lambert);
          }
          std::vector<double> buffer, lambert_cost(data.images), specular_cost(data.images);
          NormalSearch search(
              table, 16,
              fit.ks_prior ? std::optional(internal::Luminance(*fit.ks_prior)) : std::nullopt,
              fit.ks_prior_weight);
          if (per_pixel) {
            internal::PreparePixelTestSearch(search, table);
            internal::PreparePixelTestSearch(*lambert_search, *tables.lambert);
          }
          std::vector<std::pair<double, int>> order;
          PixelLights woodham_lights(data);
          long long local = 0;
          for (std::size_t i = b; i < e; ++i) {
            const std::size_t p = tiles[tile].pixels[i];
            PixelSolution& s = solutions[p];
            if (!fitter.Prepare(p)) {
              // Dark everywhere: flagged. Fewer than 3 unsaturated observations: Woodham on them
              // all (or flagged by it).
              if (fitter.dark()) {
                s.status = PixelStatus::kDark;
              } else {
                s = Woodham(data, p, woodham, Eigen::Matrix3Xd(), order, woodham_lights, true);
              }
              continue;
            }
            const SearchResult r =
                search.Search(fitter.luminance(), fitter.usable(), fitter.threshold(),
                              o.material_known ? &ks_luminance : nullptr);
            if (r.candidate < 0 || !(r.kd > 0 || r.ks > 0)) {
              s.status = PixelStatus::kDark;  // nothing lit under any normal
              continue;
            }
            if (per_pixel) {
              // Where the object's lobe gets no weight in the pixel's fit to all its lights the two
              // models are the same there: Lambert, untested. Otherwise each model is searched on
              // each fold's training lights near the all-lights answer (the tables share their
              // directions, and the two models' answers for a pixel lie near each other: searching
              // Lambert's own on all lights as well cost a fifth of the run, and leaving it out
              // moved the seven DiLiGenT runs by 0.01° at most, harvest by −0.13°), and Lambert
              // takes the pixel only where it predicts the held-out lights clearly better
              // (kPixelModelSignificance).
              const bool lambert_wins =
                  internal::TestPixelModel(search, table, r, *lambert_search, *tables.lambert,
                                           fitter.luminance(), fitter.usable(), fitter.threshold(),
                                           fitter.brightness(), fold.data(), buffer,
                                           lambert_cost.data(), specular_cost.data())
                      .lambert;
              won[p] = lambert_wins ? 0 : 1;
              if (lambert_wins) {
                lambert_fitter->Prepare(p);
                s.normal = table.normal(r.candidate);
                lambert_fitter->Fit(s);
                local += s.iterations;
                continue;
              }
            }
            s.normal = table.normal(r.candidate);
            fitter.Fit(s);
            // With known coefficients the best candidates of other basins are fitted too
            // (SearchResult::others), and the lowest censored cost after the local fit wins: on a
            // torus one pixel in 5 400 kept a wrong basin 4.9° off without. With estimated ones on
            // photos the lowest cost is not the better normal often enough: on the seven DiLiGenT
            // runs it moved four by −0.02 to −0.09°, harvest by +0.26°, at a third more time.
            for (const int other : r.others) {
              if (other < 0 || !o.material_known) break;
              PixelSolution alternative;
              alternative.normal = table.normal(other);
              fitter.Fit(alternative);
              s.iterations += alternative.iterations;
              if (alternative.cost < s.cost) {
                alternative.iterations = s.iterations;
                s = alternative;
              }
            }
            local += s.iterations;
          }
          iterations += local;
          const std::size_t now = done += e - b;
          if (o.progress) o.progress(static_cast<double>(now) / pixels);
        });
    result.summary.iterations = iterations.load();
    result.summary.solve_seconds = SecondsSince(start);
  }

  internal::AssembleNormals(data, o, solutions, won, per_pixel_map, result);
  return result;
}

void FinishNormals(NormalResult& result, const NormalPlan& plan,
                   const std::vector<Vec3f>& sample_ks) {
  const NormalOptions& o = plan.options;
  // Oren–Nayar's rough diffuse term has no lobe: its one coefficient is the facets' slope.
  const bool rough = o.model == reflectance::Lobe::kOrenNayar;
  const bool specular = o.model != reflectance::Lobe::kLambert && !rough;
  if (o.material_known) {
    result.ks = o.ks;
  } else if (plan.requested_model != reflectance::Lobe::kLambert) {
    result.material_estimated = specular || rough;
    result.specular_identifiable = specular;
    result.ks = specular ? MedianKs(sample_ks) : Vec3d::Zero();
    result.specular_note =
        specular ? "model chosen by held-out prediction (" + plan.model_choice.note +
                       "); ks per pixel in specular.exr, this is the median where the lobe was kept"
        : rough ? "Oren-Nayar's rough diffuse term chosen by held-out prediction (" +
                      plan.model_choice.note +
                      "); its facet slope in radians is the shininess, no specular term"
                : "no specular model predicts held-out observations better than Lambert's (" +
                      plan.model_choice.note + ")";
  }
}

NormalResult EstimateNormals(const PhotometricData& data, const NormalOptions& options) {
  CheckInputs(data, options);
  const std::vector<std::size_t> sample =
      PlanSampleIndices(data.pixel_count(), options.plan_sample);
  const NormalPlan plan = sample.size() == data.pixel_count()
                              ? PlanNormals(data, options)
                              : PlanNormals(SubsetObservations(data, sample), options);
  NormalResult result = SolveNormalsWithPlan(data, plan);
  std::vector<Vec3f> sample_ks;
  AppendSampleSpecular(result, data, sample, sample_ks);
  FinishNormals(result, plan, sample_ks);
  return result;
}

NormalResult RecoverNormals(const PhotometricData& data, const NormalOptions& options) {
  if (data.images >= 3) return EstimateNormals(data, options);
  if (!options.material_known || !options.known_albedo) {
    throw std::invalid_argument("with " + std::to_string(data.images) +
                                " image(s) the coefficients must be known, kd (a uniform albedo) "
                                "included");
  }
  FewImageOptions few;
  few.model = options.model;
  few.material.kd = *options.known_albedo;
  few.material.ks = options.ks;
  few.material.shininess = options.shininess;
  few.ambient_term = options.ambient_term;
  few.threads = options.threads;
  few.progress = options.progress;
  const FewImageResult r = EstimateNormalsFewImages(data, few);
  NormalResult result;
  result.model = options.model;
  result.normals = r.normals;
  result.residual = r.residual;
  result.ambiguity_deg = r.ambiguity_deg;
  result.ks = options.ks;
  result.shininess = options.shininess;
  result.ambient_term = options.ambient_term;
  result.albedo = ImageF(data.width, data.height, 3);
  for (int p : data.pixels) {
    for (int c = 0; c < 3; ++c)
      result.albedo.pixels[3 * p + c] = static_cast<float>(few.material.kd[c]);
  }
  result.summary.success = true;
  result.summary.pixels = data.pixel_count();
  result.summary.solve_seconds = r.solve_seconds;
  result.summary.iterations = r.iterations;
  result.summary.message = r.message;
  return result;
}

}  // namespace iphong::solve
