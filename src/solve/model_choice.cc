#include "solve/model_choice.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>

#include "core/golden_section.h"
#include "solve/heldout_internal.h"
#include "solve/woodham.h"

namespace iphong::solve {

using internal::HeldOutPixels;
using internal::Sample;
using internal::SamplePixels;
using internal::SetHeldOutSummary;
using internal::SharedSpecular;

namespace {

// The golden-section refinement of a shininess or a slope within √2 of the grid's best: its
// bracket, ln 2 wide in the parameter's log, narrows to ln 2 · r³ (r the golden ratio's inverse),
// so the refined value is resolved to about half that, ±8 %.
constexpr int kRefineIterations = 3;
constexpr double kSlopeStandardErrors = 2;
double RefinedResolution() {
  return 0.5 * std::log(2.0) * std::pow((std::sqrt(5.0) - 1) / 2, kRefineIterations);
}

// Whether the rough diffuse term's facet slope is one property of the surface (ChooseModel):
// `costs` are the held-out costs per pixel of `sample` at each slope scored on all of it
// (`slopes`). The sample is split at the median N·V of its pixels' Woodham normals into a frontal
// and an oblique half, and each half's best slope is found. One slope must serve both: some
// scored slope must predict each half within kSlopeStandardErrors standard errors of that half's
// best (paired over the half). Two, not the choice's one: each half's best is chosen on the
// pixels it is compared on, and starts ahead by that selection alone, most on the frontal half,
// where the term claims least and the slope is least determined. Halves whose bests are within
// the refinement's resolution of each other (RefinedResolution) agree whatever the costs say: a
// capture of many observations shows as significant a difference the choice does not resolve,
// as a model the qualitative term only approximates leaves (the paper's full one, with its
// interreflection term). `why` is set when they disagree.
bool OneSlope(const PhotometricData& data, const std::vector<Sample>& sample,
              const std::vector<const std::vector<double>*>& costs,
              const std::vector<double>& slopes, const ModelChoiceSettings& settings,
              std::string* why) {
  if (costs.size() < 2 || sample.size() < 2) return true;
  WoodhamSettings woodham;
  woodham.saturation = settings.fit.saturation;
  woodham.ambient_term = settings.fit.ambient_term;
  const Eigen::Matrix3Xd pinv = data.near() ? Eigen::Matrix3Xd() : WoodhamPseudoInverse(data);
  std::vector<std::pair<double, int>> order;
  PixelLights lights(data);
  std::vector<double> facing(sample.size(), -1.0);
  for (std::size_t i = 0; i < sample.size(); ++i) {
    const internal::PixelSolution w =
        Woodham(data, sample[i].pixel, woodham, pinv, order, lights, false);
    lights.At(sample[i].pixel);
    if (w.normal.allFinite() && !w.normal.isZero()) facing[i] = w.normal.dot(lights.view());
  }
  std::vector<double> sorted = facing;
  const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  std::array<std::vector<double>, 2> half;  // frontal, oblique
  for (auto& h : half) h.assign(sample.size(), 0.0);
  for (std::size_t i = 0; i < sample.size(); ++i) (facing[i] >= *middle ? half[0] : half[1])[i] = 1;
  std::array<std::size_t, 2> best = {0, 0};
  for (int h = 0; h < 2; ++h) {
    double lowest = INFINITY;
    for (std::size_t c = 0; c < costs.size(); ++c) {
      const double mean =
          PairedDifference(costs[c]->data(), nullptr, sample.size(), half[h].data()).first;
      if (mean < lowest) lowest = mean, best[h] = c;
    }
  }
  if (std::abs(std::log(slopes[best[0]] / slopes[best[1]])) <= RefinedResolution()) return true;
  // Each slope's excess over each half's best, in that half's standard errors: the worse half's.
  double least = INFINITY;
  for (std::size_t c = 0; c < costs.size(); ++c) {
    double worst = 0;
    for (int h = 0; h < 2; ++h) {
      const auto [excess, error] =
          PairedDifference(costs[c]->data(), costs[best[h]]->data(), sample.size(), half[h].data());
      worst = std::max(worst, excess > 0 ? excess / std::max(error, 1e-300) : 0.0);
    }
    least = std::min(least, worst);
  }
  if (least <= kSlopeStandardErrors) return true;
  char text[200];
  std::snprintf(text, sizeof text,
                "; Oren-Nayar's rough term left out: the frontal half prefers slope %.3g, the "
                "oblique half %.3g, and no slope predicts both within %.3g standard errors",
                slopes[best[0]], slopes[best[1]], least);
  *why = text;
  return false;
}

}  // namespace

ModelChoice ChooseModel(const PhotometricData& data, std::vector<ModelCandidate> family,
                        const ModelChoiceSettings& settings) {
  ModelChoice choice;
  const int k = data.images;
  if (k < 6 || family.size() == 1) {
    choice.chosen = family.size() == 1 ? family[0] : ModelCandidate{};
    choice.note = family.size() == 1 ? "the only model asked for"
                                     : "fewer than 6 lights: no half can be held out to test a "
                                       "specular model, so the Lambertian one is used";
    return choice;
  }
  // Two halves of the lights, fixed for every model: a shuffled alternation, so that each half
  // covers the directions of the whole set.
  // Folds of the lights, fixed for every model: each fit sees at least kMinTrainingLights
  // lights (six per unknown of normal, kd and ks), or all but one — two halves for DiLiGenT's
  // 96, leave-one-out for 24 or fewer. A shuffled alternation, so each fold spans the set.
  const std::vector<int> fold = LightFolds(k);
  choice.fold = fold;
  // What the observations are taken to be: as recorded, less the estimated ambient term, and,
  // for integer codes, half a code brighter (truncated rather than rounded). Each variant has
  // its own sample of the same pixels.
  const Vec3d ambient = EstimateAmbient(data);
  choice.code_step = IntegerCodeStep(data);
  const double half_code = choice.code_step >= kMinTestedCodeStep ? choice.code_step / 2 : 0.0;
  const auto settings_for = [&](const ModelCandidate& m) {
    ModelChoiceSettings s = settings;
    s.fit.ambient_term = m.ambient_term;
    s.fit.code_offset = m.code_offset;
    return s;
  };
  std::map<std::pair<bool, bool>, std::vector<Sample>> samples;
  const auto sample_of = [&](const ModelCandidate& m) -> const std::vector<Sample>& {
    const auto key = std::pair(!m.ambient_term.isZero(), m.code_offset != 0);
    auto it = samples.find(key);
    if (it == samples.end())
      it = samples.emplace(key, SamplePixels(data, settings_for(m), &fold)).first;
    return it->second;
  };
  const std::vector<Sample>& sample = sample_of(ModelCandidate{});
  choice.pixels = sample.size();
  // Each model is scored first on every kRaceShare-th pixel of the sample (spread over the
  // object like the sample); it is scored on the rest only if it is not already clearly worse
  // than the lowest fully scored model, paired over those pixels (see kRaceStandardErrors).
  const bool race = sample.size() >= kRaceShare * kRaceMinimumPixels;
  std::vector<char> first(sample.size()), rest(sample.size());
  std::vector<double> first_use(sample.size());
  for (std::size_t i = 0; i < sample.size(); ++i) {
    first[i] = !race || i % kRaceShare == 0;
    rest[i] = !first[i];
    first_use[i] = first[i];
  }
  std::vector<std::vector<double>> costs;  // per scored model, per sample pixel
  std::vector<char> complete;              // scored on the whole sample
  std::optional<std::size_t> leader;       // the lowest complete model
  const auto held_out = [&](ModelCandidate m) {
    std::vector<double> cost, angle;
    const std::vector<Sample>& pixels = sample_of(m);
    internal::HeldOutTables tables;  // the quarter's, reused for the rest
    HeldOutPixels(data, m, pixels, fold, settings_for(m), &first, cost, angle,
                  race ? &tables : nullptr);
    bool whole = true;
    if (race && leader) {
      const auto [mean, error] =
          PairedDifference(cost.data(), costs[*leader].data(), cost.size(), first_use.data());
      if (mean > 0 && mean > kRaceStandardErrors * error) {
        // Not scored further: its cost the leader's plus the paired excess measured so far.
        std::vector<double> part, part_angle;
        for (std::size_t i = 0; i < cost.size(); ++i) {
          if (first[i]) part.push_back(cost[i]), part_angle.push_back(angle[i]);
        }
        SetHeldOutSummary(m, part, part_angle);
        m.heldout_cost = choice.scored[*leader].heldout_cost + mean;
        m.heldout_pixels = part.size();
        whole = false;
      }
    }
    if (whole) {
      if (race) {
        std::vector<double> more, more_angle;
        HeldOutPixels(data, m, pixels, fold, settings_for(m), &rest, more, more_angle, &tables);
        for (std::size_t i = 0; i < cost.size(); ++i) {
          if (rest[i]) cost[i] = more[i], angle[i] = more_angle[i];
        }
      }
      SetHeldOutSummary(m, cost, angle);
      m.heldout_pixels = cost.size();
      if (!leader || m.heldout_cost < choice.scored[*leader].heldout_cost) {
        leader = choice.scored.size();
      }
    }
    choice.scored.push_back(m);
    costs.push_back(std::move(cost));
    complete.push_back(whole);
    return m.heldout_cost;
  };
  if (sample.empty()) {
    choice.chosen = family.front();
    choice.note = "no pixel with 3 usable observations in each half: not tested";
    return choice;
  }
  // Every model of the grid in each variant, so the model and what the observations are taken
  // to be are chosen together: a lobe chosen without the ambient term bends to imitate it (a
  // sphere under a ring of lights at ambient 1 chose the broadest lobe, n 4.8 for a true 20, and
  // came out 0.66° off). DiLiGenT's truncated 8-bit crops predict their held-out lights 5–25 %
  // better at their codes' middle, with every model. A variant is compared only on the same
  // pixels (none changed its usable count).
  std::vector<ModelCandidate> variants;  // the observations' variants; the first as recorded
  for (const bool with_ambient : {false, true}) {
    if (with_ambient && ambient.isZero()) continue;
    for (const bool truncated : {false, true}) {
      if (truncated && half_code == 0) continue;
      ModelCandidate v;
      if (with_ambient) v.ambient_term = ambient;
      if (truncated) v.code_offset = half_code;
      if (sample_of(v).size() == sample.size()) variants.push_back(v);
    }
  }
  const std::vector<ModelCandidate> grid = family;
  // The foil is scored only once a mirror lobe of the family predicts better than Lambert: it is
  // there to take what such a lobe might be absorbing, so where none does (a matte object) the
  // choice costs what it did without it. Asked for alone (`only`), it is scored.
  const auto is_mirror = [](reflectance::Lobe lobe) {
    return lobe == reflectance::Lobe::kPhong || lobe == reflectance::Lobe::kBlinnPhong;
  };
  const bool family_has_mirror = std::any_of(
      grid.begin(), grid.end(), [&](const ModelCandidate& m) { return is_mirror(m.lobe); });
  const auto mirror_beats_lambert = [&] {
    double lambert = INFINITY, mirror = INFINITY;
    for (std::size_t i = 0; i < choice.scored.size(); ++i) {
      if (!complete[i]) continue;
      const ModelCandidate& m = choice.scored[i];
      if (m.lobe == reflectance::Lobe::kLambert) lambert = std::min(lambert, m.heldout_cost);
      if (is_mirror(m.lobe)) mirror = std::min(mirror, m.heldout_cost);
    }
    return mirror < lambert;
  };
  // The codes' reading (rounded or truncated) is the camera's, and every model shows it alike
  // (DiLiGenT's 8-bit crops predict 5–25 % better at their codes' middle with each): where a
  // variant differs from the one before it only by that reading, it is scored at that variant's
  // best of each lobe, not over the whole grid (UW's 12-light cat: 16 scorings, was 26).
  const auto in_variant = [](const ModelCandidate& m, const ModelCandidate& v) {
    return m.ambient_term == v.ambient_term && m.code_offset == v.code_offset;
  };
  // The lowest of `lobe`'s first `end` scores (in `variant`'s observations only, if given). Only
  // complete models: one that dropped out of the race has no cost to compare.
  const auto best_of_lobe = [&](reflectance::Lobe lobe, std::size_t end,
                                const ModelCandidate* variant) {
    std::optional<std::size_t> best;
    for (std::size_t i = 0; i < end; ++i) {
      const ModelCandidate& m = choice.scored[i];
      if (complete[i] && m.lobe == lobe && (!variant || in_variant(m, *variant)) &&
          (!best || m.heldout_cost < choice.scored[*best].heldout_cost)) {
        best = i;
      }
    }
    return best;
  };
  for (std::size_t vi = 0; vi < variants.size(); ++vi) {
    const ModelCandidate& v = variants[vi];
    std::vector<ModelCandidate> models;
    if (vi > 0 && v.code_offset != 0 && variants[vi - 1].code_offset == 0 &&
        variants[vi - 1].ambient_term == v.ambient_term) {
      for (const ModelCandidate& g : grid) {
        if (std::any_of(models.begin(), models.end(),
                        [&](const ModelCandidate& m) { return m.lobe == g.lobe; })) {
          continue;  // this lobe's best is in already
        }
        const auto best = best_of_lobe(g.lobe, choice.scored.size(), &variants[vi - 1]);
        if (best) models.push_back(choice.scored[*best]);
      }
    } else {
      models = grid;
    }
    // The rough term's slopes ascend from the cosine: once one predicts worse than the slope
    // before it, or drops out of the race, the held-out cost has passed its least along σ (the
    // term's departure from the cosine only grows with it) and the steeper slopes are not
    // scored. A glossy object then pays a quarter of one scoring for the term.
    std::optional<double> rough_before;
    bool rough_done = false;
    for (ModelCandidate m : models) {
      m.ambient_term = v.ambient_term;
      m.code_offset = v.code_offset;
      if (m.lobe == reflectance::Lobe::kNormalCentred && family_has_mirror &&
          !mirror_beats_lambert()) {
        continue;
      }
      if (m.lobe == reflectance::Lobe::kOrenNayar) {
        if (rough_done) continue;
        const double cost = held_out(m);
        rough_done = !complete.back() || (rough_before && cost > *rough_before);
        rough_before = cost;
        continue;
      }
      held_out(m);
    }
  }
  // Each lobe's shininess refined from its own best grid point, so that the grid does not decide
  // between two lobes that predict alike (Phong n and Blinn-Phong about 4n): one step of √2
  // each way (not wider than a highlight), then a golden-section search of log n within √2 either
  // side of the best of the three (five more evaluations: within 4%).
  // A lobe is refined only where its grid best predicts better than Lambert does: refining
  // chooses among lobes that will be used, and a lobe no grid point of which beats Lambert would
  // have to gain more than a standard error within a step of √2 to be chosen (a matte object's
  // lobes all trail Lambert: a third of its choice was spent refining them).
  const std::size_t grid_size = choice.scored.size();
  double lambert_cost = INFINITY;
  for (std::size_t i = 0; i < grid_size; ++i) {
    if (complete[i] && choice.scored[i].lobe == reflectance::Lobe::kLambert) {
      lambert_cost = std::min(lambert_cost, choice.scored[i].heldout_cost);
    }
  }
  for (const reflectance::Lobe lobe :
       {reflectance::Lobe::kPhong, reflectance::Lobe::kBlinnPhong,
        reflectance::Lobe::kNormalCentred, reflectance::Lobe::kOrenNayar}) {
    // A lobe none of whose grid points stayed in the race is not refined.
    const auto best_of = [&](std::size_t end, const ModelCandidate* variant) {
      return best_of_lobe(lobe, end, variant);
    };
    const std::optional<std::size_t> grid_best = best_of(grid_size, nullptr);
    if (!grid_best || !(choice.scored[*grid_best].heldout_cost < lambert_cost)) continue;
    // The foil is refined only where its grid best is not clearly behind the grid's best model
    // (one paired standard error): it is there to take what no highlight explains, and where a
    // mirror lobe predicts clearly better on the grid a step of √2 will not turn that around.
    if (lobe == reflectance::Lobe::kNormalCentred && leader) {
      const auto [mean, error] =
          PairedDifference(costs[*grid_best].data(), costs[*leader].data(), costs[*leader].size());
      if (mean > error) continue;
    }
    const ModelCandidate start = choice.scored[*grid_best];
    const auto evaluate = [&](double shininess) {
      ModelCandidate m = start;
      m.shininess = shininess;
      return held_out(m);
    };
    for (double f : {std::sqrt(0.5), std::sqrt(2.0)}) {
      if (start.shininess * f >= MinimumShininess(lobe)) evaluate(start.shininess * f);
    }
    const double centre = choice.scored[*best_of(choice.scored.size(), &start)].shininess;
    GoldenSectionLog(std::max(centre / std::sqrt(2.0), MinimumShininess(lobe)),
                     centre * std::sqrt(2.0), kRefineIterations, evaluate);
    // The other readings of the observations at the refined shininess, so that a reading is
    // chosen at the same lobe and not by which one had the better grid point (a grid step of 2
    // can cost more than the reading does: a truncated 8-bit sphere of Phong 50 kept its codes
    // as recorded because the grid's best was in that reading, 1.21° against 0.8° at their middle).
    const ModelCandidate refined = choice.scored[*best_of(choice.scored.size(), &start)];
    for (const ModelCandidate& v : variants) {
      if (in_variant(refined, v)) continue;
      ModelCandidate m = refined;
      m.ambient_term = v.ambient_term;
      m.code_offset = v.code_offset;
      held_out(m);
    }
  }
  // The lowest complete model, among mirror lobes and Lambert only with `mirror_only`.
  const auto is_foil = [&](std::size_t i) {
    return choice.scored[i].lobe == reflectance::Lobe::kNormalCentred;
  };
  // Without the foil: the mirror lobes and Lambert (Oren–Nayar's diffuse term is no highlight).
  const auto outside_mirror = [&](std::size_t i) {
    return !is_mirror(choice.scored[i].lobe) &&
           choice.scored[i].lobe != reflectance::Lobe::kLambert;
  };
  const auto lowest = [&](bool mirror_only) {
    std::optional<std::size_t> best;
    for (std::size_t i = 0; i < choice.scored.size(); ++i) {
      if (complete[i] && !(mirror_only && outside_mirror(i)) &&
          (!best || choice.scored[i].heldout_cost < choice.scored[*best].heldout_cost)) {
        best = i;
      }
    }
    return best;
  };
  std::string rough_left_out;  // why the rough term left the choice, for the note
  // Oren–Nayar's term stands for a surface of V-grooves of one slope σ, and its departure from
  // the cosine grows with the view's obliquity: a misfit it absorbs instead — grazing light
  // falling off faster than the cosine, a renderer's interpolated normals darkening the terminator
  // band — wants a different σ where the surface faces the camera than where it turns away
  // (docs/guides/normals.md has the measurements). So where the rough term could be chosen
  // (it leads or ties the leader), the slopes scored on the whole sample are compared on its
  // frontal and oblique halves (OneSlope); where no slope serves both halves the
  // term leaves the choice.
  {
    const auto on_best = best_of_lobe(reflectance::Lobe::kOrenNayar, choice.scored.size(), nullptr);
    // Asked for alone (no other model scored), the term stays whatever its halves say.
    const bool others = std::any_of(
        choice.scored.begin(), choice.scored.end(),
        [](const ModelCandidate& m) { return m.lobe != reflectance::Lobe::kOrenNayar; });
    const bool contender = others && on_best && leader && [&] {
      const auto [mean, error] =
          PairedDifference(costs[*on_best].data(), costs[*leader].data(), costs[*leader].size());
      return mean <= error;
    }();
    std::vector<const std::vector<double>*> slope_costs;
    std::vector<double> slopes;
    for (std::size_t i = 0; contender && i < choice.scored.size(); ++i) {
      if (complete[i] && choice.scored[i].lobe == reflectance::Lobe::kOrenNayar &&
          in_variant(choice.scored[i], choice.scored[*on_best])) {
        slope_costs.push_back(&costs[i]);
        slopes.push_back(choice.scored[i].shininess);
      }
    }
    if (contender && !OneSlope(data, sample_of(choice.scored[*on_best]), slope_costs, slopes,
                               settings, &rough_left_out)) {
      // Out of the choice as a model dropped from the race is: no longer a complete score.
      for (std::size_t i = 0; i < choice.scored.size(); ++i) {
        if (choice.scored[i].lobe == reflectance::Lobe::kOrenNayar) complete[i] = false;
      }
      leader = lowest(false);  // the lowest of the rest
    }
  }
  // How far each pixel's ks may stray from the object's: free, or pulled toward it with the
  // weight of 1 or 10 observations of the lobe's peak, also by prediction — for the foil's best
  // and the mirror lobes' best when the foil leads, so the highlight weighed against it is the
  // one the choice would make without it.
  for (const bool mirror_only : {false, true}) {
    const std::optional<std::size_t> at = lowest(mirror_only);
    if (!at || (mirror_only && !is_foil(*leader))) continue;
    const ModelCandidate lobe_best = choice.scored[*at];
    if (lobe_best.lobe == reflectance::Lobe::kLambert ||
        lobe_best.lobe == reflectance::Lobe::kOrenNayar) {
      continue;  // no ks
    }
    const Vec3d shared = SharedSpecular(data, lobe_best, settings_for(lobe_best));
    for (double weight : {1.0, 10.0}) {
      ModelCandidate m = lobe_best;
      m.ks_prior = shared;
      m.ks_prior_weight = weight;
      held_out(m);
    }
  }
  // Prediction first; among the models whose held-out cost is not distinguishable from the
  // lowest (paired over the same pixels, within one standard error), Lambert if it is one of
  // them — a specular model is used only where it predicts better (a matte object's lobes all
  // fit ks ≈ 0 and tie with it) — else the one whose two halves agree best on the normal: two
  // models can predict the images equally well while one of them leaves the normal less
  // determined.
  const auto preferred = [&](std::size_t i, std::size_t j) {
    const bool lambert_i = choice.scored[i].lobe == reflectance::Lobe::kLambert;
    const bool lambert_j = choice.scored[j].lobe == reflectance::Lobe::kLambert;
    if (lambert_i != lambert_j) return lambert_i;
    return choice.scored[i].fold_angle_deg < choice.scored[j].fold_angle_deg;
  };
  const auto pick_among = [&](bool mirror_only) {
    const std::size_t lowest_index = *lowest(mirror_only);
    std::size_t pick = lowest_index;
    for (std::size_t i = 0; i < choice.scored.size(); ++i) {
      if (!complete[i] || (mirror_only && outside_mirror(i))) continue;
      const auto [mean, error] =
          PairedDifference(costs[i].data(), costs[lowest_index].data(), costs[i].size());
      if (mean <= error && preferred(i, pick)) pick = i;
    }
    return pick;
  };
  const std::size_t pick = pick_among(false);
  const ModelCandidate best = choice.scored[pick];
  choice.chosen = best;
  // The foil predicting best says the data's departure from Lambert follows the normal, yet a
  // highlight can predict a little worse and still be the truth: where the choice without the
  // foil takes a mirror lobe (one that beats Lambert beyond a standard error), the plan keeps
  // whichever of the two gives normals that make a surface (highlight_check.h).
  if (is_foil(pick) && lowest(true)) {
    const std::size_t mirror = pick_among(true);
    if (choice.scored[mirror].lobe != reflectance::Lobe::kLambert) {
      choice.highlight = choice.scored[mirror];
    }
  }
  const auto lambert = std::find_if(choice.scored.begin(), choice.scored.end(), [](const auto& m) {
    return m.lobe == reflectance::Lobe::kLambert;
  });
  char text[160];
  std::snprintf(text, sizeof text, "held-out cost %.3g per pixel on %zu pixels", best.heldout_cost,
                sample.size());
  choice.note = text;
  if (lambert != choice.scored.end() && best.lobe != reflectance::Lobe::kLambert) {
    std::snprintf(text, sizeof text, ", Lambert's %.3g", lambert->heldout_cost);
    choice.note += text;
  }
  choice.note += rough_left_out;
  if (half_code != 0) {
    choice.note += best.code_offset != 0 ? "; integer codes taken as truncated (half a code added)"
                                         : "; integer codes taken as rounded";
  }
  return choice;
}

}  // namespace iphong::solve
