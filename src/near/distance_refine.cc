// D and its centre chosen again on a near pass's surface (distance_choice.h says why).
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "core/golden_section.h"
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
  // The foil cannot judge a distance (distance_choice.cc): the diffuse test does.
  diffuse = diffuse || PlanModel(plan).lobe == reflectance::Lobe::kNormalCentred;
  const auto [model, settings] = DistanceTest(plan, o, diffuse, &starts);
  const std::string criterion =
      std::string(diffuse ? "diffuse" : "model") + ", again on the near surface";
  RefinedDistance best{distance, behind, 0, 0, false};
  double best_cost = std::numeric_limits<double>::infinity();
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
  const double start_cost = score(distance, behind);
  if (surface.relief > 0.5) {
    // The first choice's neighbours: a tenth farther, and the centre a quarter of the rim deeper,
    // each the other way where that would leave the range the first choice searched.
    const double log_d = std::log(distance);
    const auto inside = [&](double l, double b) {
      return InDistanceRange(l, b, surface.relief, result.object_size_px);
    };
    const double step_d = inside(log_d + 0.1, behind) ? 0.1 : -0.1;
    const double step_b = inside(log_d, behind + 0.25 * surface.relief) ? 0.25 * surface.relief
                                                                        : -0.25 * surface.relief;
    SearchDistanceAndCentre(
        {{log_d, behind}, {log_d + step_d, behind}, {log_d, behind + step_b}},
        {start_cost, score(std::exp(log_d + step_d), behind), score(distance, behind + step_b)},
        surface.relief, result.object_size_px, score);
  } else {
    // A flat object's centre is its centroid (distance_choice.cc): D alone.
    GoldenSectionLog(std::max(kNearestSizes * result.object_size_px, distance / 1.5),
                     std::min(kDistanceGrid[std::size(kDistanceGrid) - 1] * result.object_size_px,
                              distance * 1.5),
                     6, [&](double d) { return score(d, behind); });
  }
  std::tie(best.gain, best.gain_error) =
      solve::PairedDifference(start_costs.data(), best_costs.data(), start_costs.size());
  // Far lights hardly change the predictions with D or the centre, and there the simplex's best
  // is noise: the first choice stands unless the new one predicts better beyond one paired
  // standard error, the line every choice of D draws (DiLiGenT's ball at 27 object sizes: a gain
  // of 0.07 t² moved the centre by a rim's depth).
  best.moved = best.gain > best.gain_error;
  if (o.log) {
    char line[300];
    std::snprintf(line, sizeof line,
                  "the %s again on the near surface: best %.4g px, the centre %.3g px behind "
                  "(from %.4g px, %.3g px), held-out gain %.4g +- %.2g%s",
                  diffuse ? "diffuse term" : "object's model", best.distance, best.behind, distance,
                  behind, best.gain, best.gain_error, best.moved ? "" : ": kept");
    o.log(line);
  }
  if (!best.moved) best.distance = distance, best.behind = behind;
  return best;
}

}  // namespace iphong::near::internal
