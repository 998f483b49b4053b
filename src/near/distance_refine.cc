// D and its centre chosen again on a near pass's surface (distance_choice.h says why).
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "core/golden_section.h"
#include "core/nelder_mead.h"
#include "near/distance_choice.h"
#include "near/internal.h"
#include "solve/assemble.h"
#include "solve/model_choice.h"

namespace iphong::near::internal {

using solve::PhotometricData;

RefinedDistance RefineDistance(const DistanceCapture& capture, const solve::NormalPlan& plan,
                               const EffectiveDistanceOptions& o, const DistanceSurface& surface,
                               const std::vector<double>& depth, const solve::NormalResult& from,
                               bool diffuse, double distance, double behind,
                               EffectiveDistanceResult& result) {
  const PhotometricData& data = *capture.layout;
  const std::vector<std::size_t> spread =
      solve::SpreadIndices(data.pixel_count(), o.normals.model_sample);
  const PhotometricData sub = std::move(capture.observations({spread})[0]);
  std::vector<double> sub_depth;
  std::vector<Vec3d> starts;
  {
    const std::vector<Vec3d> all = NormalsPerPixel(from, data);
    for (std::size_t i : spread) sub_depth.push_back(depth[i]), starts.push_back(all[i]);
  }
  std::vector<std::size_t> sample(spread.size());
  for (std::size_t i = 0; i < sample.size(); ++i) sample[i] = i;
  const std::vector<int> fold =
      plan.model_choice.fold.empty() ? solve::LightFolds(data.images) : plan.model_choice.fold;
  solve::ModelCandidate model = PlanModel(plan);
  solve::ModelChoiceSettings settings;
  settings.fit = solve::internal::FitSettingsOf(plan.options);
  settings.fit.shading_weights = {};  // unweighted, as the first choice's fits
  settings.sample = o.normals.model_sample;
  settings.threads = o.normals.threads;
  settings.starts = &starts;
  // The foil cannot judge a distance (distance_choice.cc): the diffuse test does.
  diffuse = diffuse || model.lobe == reflectance::Lobe::kNormalCentred;
  if (diffuse) solve::MakeDiffuseTest(model, settings);
  const std::string criterion =
      std::string(diffuse ? "diffuse" : "model") + ", again on the near surface";
  RefinedDistance best{distance, behind, 0, 0};
  double best_cost = std::numeric_limits<double>::infinity(), start_cost = best_cost;
  std::vector<double> start_costs, best_costs;
  const auto score = [&](double d, double b) {
    solve::ModelCandidate m = model;
    std::vector<double> c = solve::PixelHeldOutCosts(
        NearData(sub, surface.frame, sub_depth, surface.CentreAt(b), d), m, sample, fold, settings);
    result.scored.push_back({d, b, m.heldout_cost, m.heldout_error, criterion});
    if (start_costs.empty()) start_costs = c;
    if (m.heldout_cost < best_cost) {
      best_cost = m.heldout_cost, best.distance = d, best.behind = b;
      best_costs = std::move(c);
    }
    return m.heldout_cost;
  };
  start_cost = score(distance, behind);
  const double log_lo = std::log(kNearestSizes * result.object_size_px);
  const double log_hi =
      std::log(kDistanceGrid[std::size(kDistanceGrid) - 1] * result.object_size_px);
  const bool deep = surface.relief > 0.5;
  if (deep) {
    // The first choice's neighbours: a tenth farther, and the centre a quarter of the rim deeper
    // (each the other way where that would leave the range the first choice searched).
    const double step_d = std::log(distance) + 0.1 <= log_hi ? 0.1 : -0.1;
    const double step_b =
        0.25 * surface.relief *
        (behind + 0.25 * surface.relief <= kDeepestRims * surface.relief ? 1 : -1);
    std::vector<std::vector<double>> simplex = {{std::log(distance), behind},
                                                {std::log(distance) + step_d, behind},
                                                {std::log(distance), behind + step_b}};
    std::vector<double> costs = {start_cost, score(std::exp(simplex[1][0]), behind),
                                 score(distance, behind + step_b)};
    NelderMead(std::move(simplex), std::move(costs), {0.02, 0.05 * surface.relief}, 30,
               [&](const std::vector<double>& p) {
                 if (!(p[0] >= log_lo && p[0] <= log_hi && p[1] >= 0 &&
                       p[1] <= kDeepestRims * surface.relief)) {
                   return std::numeric_limits<double>::infinity();
                 }
                 return score(std::exp(p[0]), p[1]);
               });
  } else {
    GoldenSectionLog(std::max(std::exp(log_lo), distance / 1.5),
                     std::min(std::exp(log_hi), distance * 1.5), 6,
                     [&](double d) { return score(d, behind); });
  }
  std::tie(best.gain, best.gain_error) =
      solve::PairedDifference(start_costs.data(), best_costs.data(), start_costs.size());
  // Far lights hardly change the predictions with D or the centre, and there the simplex's best
  // is noise: the first choice stands unless the new one predicts better beyond one paired
  // standard error, the line every choice of D draws (DiLiGenT's ball at 27 object sizes: a gain
  // of 0.07 t² moved the centre by a rim's depth).
  const bool moves = best.gain > best.gain_error;
  if (o.log) {
    char line[300];
    std::snprintf(line, sizeof line,
                  "the %s again on the near surface: best %.4g px, the centre %.3g px behind "
                  "(from %.4g px, %.3g px), held-out gain %.4g +- %.2g%s",
                  diffuse ? "diffuse term" : "object's model", best.distance, best.behind, distance,
                  behind, best.gain, best.gain_error, moves ? "" : ": kept");
    o.log(line);
  }
  if (!moves) best.distance = distance, best.behind = behind;
  return best;
}

}  // namespace iphong::near::internal
