#include "near/effective_distance.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>

#include "core/golden_section.h"
#include "core/timing.h"
#include "near/internal.h"
#include "reflectance/material.h"
#include "solve/assemble.h"
#include "solve/model_choice.h"

namespace iphong::near {
namespace {

using solve::PhotometricData;
using namespace internal;

// Candidates for D, in the object's sizes (the mask's larger side): far enough apart that the
// grid's neighbours bracket the best, from nearer than any photometric rig to 32 sizes. Beyond
// that a light's direction turns by under 1.8° across the object and its irradiance changes by
// under ±6 %, under what a photograph's normals are good to: there the held-out tests' "gains"
// were model misfit, not nearness (a distant render with an ambient term chose 92 object sizes by
// 0.3 % of its cost, beyond three standard errors).
constexpr double kDistanceGrid[] = {2, 3, 4, 6, 8, 12, 16, 24, 32};

// data's observations under point lights at c + D·L_j with the intensity they have at c, seen
// from the points of `depth` (orthographic, heights in pixels: depth = −height), or from
// `points` (one per pixel) where given.
PhotometricData NearData(const PhotometricData& data, const geometry::HeightMapFrame& frame,
                         const std::vector<double>& depth, const Vec3d& centre, double distance,
                         const std::vector<Vec3d>* points = nullptr) {
  PhotometricData near = data;
  near.perspective = false;
  near.point_lights.clear();
  for (int j = 0; j < data.images; ++j) {
    near.point_lights.push_back(
        reflectance::Light::Point(centre + distance * data.light_directions[j],
                                  data.light_intensities[j] * distance * distance, true));
  }
  near.points_cam = points ? *points : SurfacePoints(near, frame, depth);
  solve::SetReferenceLights(near, centre);
  return near;
}

// data without its observations.
PhotometricData LayoutOf(const PhotometricData& data) {
  PhotometricData out = solve::SubsetObservations(data, {});
  out.pixels = data.pixels;
  out.points_cam = data.points_cam;
  return out;
}

// `data`'s lights made `from`'s (point lights, the reference directions and intensities), and
// its points, when it holds every pixel `from` holds.
void WithLightsOf(PhotometricData& data, const PhotometricData& from) {
  data.perspective = from.perspective;
  data.point_lights = from.point_lights;
  data.light_directions = from.light_directions;
  data.light_intensities = from.light_intensities;
  if (data.pixel_count() == from.pixel_count()) data.points_cam = from.points_cam;
}

// The held-out model of a plan: the chosen one, or what it was given (Lambert, known
// coefficients).
solve::ModelCandidate PlanModel(const solve::NormalPlan& plan) {
  if (!plan.model_choice.scored.empty()) return plan.model_choice.chosen;
  solve::ModelCandidate m;
  m.lobe = plan.options.model;
  m.shininess = plan.options.shininess;
  m.ambient_term = plan.options.ambient_term;
  m.code_offset = plan.options.code_offset;
  return m;
}

}  // namespace

std::string EffectiveDistanceOptions::Validate() const {
  if (auto m = normals.Validate(); !m.empty()) return m;
  if (!(distance_px >= 0) || std::isnan(distance_px)) return "distance must be >= 0 (or inf)";
  if (max_passes < 1 || max_passes > 100) return "passes must be in 1..100";
  if (!(tolerance_deg > 0) || !std::isfinite(tolerance_deg)) return "tolerance must be > 0";
  if (!(min_cos > 0 && min_cos < 1)) return "min_cos must be in (0, 1)";
  return "";
}

EffectiveDistanceResult SolveEffectiveDistance(const PhotometricData& data,
                                               const EffectiveDistanceOptions& o) {
  const auto start = Clock::now();
  if (auto m = o.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = data.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (data.near()) {
    throw std::invalid_argument("an effective distance is for lights given by direction only");
  }
  if (data.pixel_count() == 0) throw std::invalid_argument("the mask selects no pixel");
  if (data.images < 3) throw std::invalid_argument("an effective distance needs 3 images");
  const std::size_t pixels = data.pixel_count();

  // The distant solve: its plan, its normals.
  const std::vector<std::size_t> plan_sample =
      solve::PlanSampleIndices(pixels, o.normals.plan_sample);
  const solve::NormalPlan plan =
      plan_sample.size() == pixels
          ? solve::PlanNormals(data, o.normals)
          : solve::PlanNormals(solve::SubsetObservations(data, plan_sample), o.normals);
  solve::NormalResult distant = solve::SolveNormalsWithPlan(data, plan);
  {
    std::vector<Vec3f> sample_ks;
    solve::AppendSampleSpecular(distant, data, plan_sample, sample_ks);
    solve::FinishNormals(distant, plan, sample_ks);
  }
  const double distant_seconds = SecondsSince(start);

  // The capture is in memory: its observations are subsets of data, and each near pass refits
  // one copy of it under the pass's lights and points.
  DistanceCapture capture;
  capture.layout = &data;
  capture.observations = [&](const std::vector<std::vector<std::size_t>>& sets) {
    std::vector<PhotometricData> out;
    for (const auto& indices : sets) out.push_back(solve::SubsetObservations(data, indices));
    return out;
  };
  std::optional<PhotometricData> near;
  capture.refine = [&](const PhotometricData& near_layout, const solve::NormalPlan& near_plan,
                       const solve::NormalResult& previous) {
    if (&near_layout == &data) return solve::RefineNormalsWithPlan(data, near_plan, previous);
    if (!near) near = data;
    WithLightsOf(*near, near_layout);
    return solve::RefineNormalsWithPlan(*near, near_plan, previous);
  };
  EffectiveDistanceResult result = ContinueEffectiveDistance(capture, plan, std::move(distant), o);
  result.distant_seconds = distant_seconds;
  result.seconds = SecondsSince(start);
  return result;
}

EffectiveDistanceResult ContinueEffectiveDistance(const DistanceCapture& capture,
                                                  const solve::NormalPlan& plan,
                                                  solve::NormalResult distant,
                                                  const EffectiveDistanceOptions& o) {
  const auto start = Clock::now();
  if (auto m = o.Validate(); !m.empty()) throw std::invalid_argument(m);
  const PhotometricData& data = *capture.layout;
  const auto say = [&](const std::string& line) {
    if (o.log) o.log(line);
  };
  EffectiveDistanceResult result;
  const std::size_t pixels = data.pixel_count();
  const std::vector<std::size_t> plan_sample =
      solve::PlanSampleIndices(pixels, o.normals.plan_sample);
  result.distant = std::move(distant);
  result.normals = result.distant;
  // At D = ∞ the foil (model_choice.h) is the only term that carries what distant Lambert lacks —
  // irradiance fall-off, a diffuse term of another shape — and that is a property of the whole
  // object, not of a material in places: the per-pixel test's choice between two diffuse shapes
  // hands pixels back to the model the object's choice rejected. Every pixel is refitted with the
  // foil from its normal (warm, no search). The choice of D below still reads the distant solve
  // with the test: with it off everywhere, that one-standard-error choice flipped.
  const auto finish_distant = [&] {
    if (plan.options.model != reflectance::Lobe::kNormalCentred ||
        result.distant.model_map.pixels.empty()) {
      return;
    }
    // Without its model map the refit gives every pixel the plan's model; the map is set aside
    // rather than the whole result copied.
    ImageF map = std::move(result.distant.model_map);
    result.distant.model_map = ImageF();
    const auto refit_start = Clock::now();
    result.normals = capture.refine(data, plan, result.distant);
    result.distant.model_map = std::move(map);
    result.foil_refit = true;
    {
      solve::NormalSummary summary = result.distant.summary;  // the refit is part of the solve
      summary.solve_seconds += result.normals.summary.solve_seconds;
      summary.iterations += result.normals.summary.iterations;
      result.normals.summary = summary;
    }
    std::vector<Vec3f> sample_ks;
    solve::AppendSampleSpecular(result.normals, data, plan_sample, sample_ks);
    solve::FinishNormals(result.normals, plan, sample_ks);
    char line[160];
    std::snprintf(line, sizeof line,
                  "distant lights with the foil: every pixel refitted with it, %.2f s",
                  SecondsSince(refit_start));
    say(line);
  };
  if (std::isinf(o.distance_px)) {
    finish_distant();
    result.seconds = SecondsSince(start);
    return result;
  }

  // Its surface, heights in pixels round the image's centre, and the object's centre and size.
  const auto choice_start = Clock::now();
  geometry::HeightMapFrame frame;  // orthographic, a pixel per unit
  std::vector<double> depth = IntegratedDepth(
      result.distant, data, frame, std::vector<double>(pixels, 0.0), o.min_cos, o.normals.threads);
  int col0 = data.width, col1 = 0, row0 = data.height, row1 = 0;
  for (int p : data.pixels) {
    col0 = std::min(col0, p % data.width), col1 = std::max(col1, p % data.width + 1);
    row0 = std::min(row0, p / data.width), row1 = std::max(row1, p / data.width + 1);
  }
  result.object_size_px = std::max(col1 - col0, row1 - row0);
  Vec3d centre = Vec3d::Zero();
  for (const Vec3d& x : SurfacePoints(data, frame, depth)) centre += x;
  centre /= static_cast<double>(pixels);

  double distance = o.distance_px;
  if (!(distance > 0)) {
    // Held-out costs on the model choice's pixels and folds, each fold's normal refined from the
    // distant one (warm), for D = ∞ and each candidate, by two tests of nearness:
    //  - the object's own model (the plan's): a sharp lobe places its highlights by each pixel's
    //    own light directions (the 16-bit DiLiGenT ball: D = 3400 px, 1.88° → 1.12°);
    //  - a Lambertian fit that leaves highlights out as it leaves shadows out: the diffuse fall-off
    //    the distance shapes, which a broad lobe imitates instead (pot1 chose Blinn-Phong 20.6 at
    //    D = ∞, and with it every finite D predicted worse).
    // D is the one whose gain over distant lights is the more significant, and only beyond one
    // paired standard error; the diffuse test's only where the object's model does not
    // contradict it (below), and either only where the surface's points predict no worse than
    // points placed by their normals (PositionCheck).
    result.chosen = true;
    const std::vector<int> fold =
        plan.model_choice.fold.empty() ? solve::LightFolds(data.images) : plan.model_choice.fold;
    // The model choice's pixels alone: each candidate's lights are set on them only.
    const std::vector<std::size_t> spread = solve::SpreadIndices(pixels, o.normals.model_sample);
    const PhotometricData sub = std::move(capture.observations({spread})[0]);
    std::vector<double> sub_depth;
    std::vector<Vec3d> starts;
    const std::vector<Vec3d> all = NormalsPerPixel(result.distant, data);
    for (std::size_t i : spread) sub_depth.push_back(depth[i]), starts.push_back(all[i]);
    std::vector<std::size_t> sample(spread.size());
    for (std::size_t i = 0; i < sample.size(); ++i) sample[i] = i;
    distance = std::numeric_limits<double>::infinity();
    // The sample's points placed by their normals, X ≈ a + s·N fitted to the surface's (a flat
    // object's normals are all alike: every point at the centroid, lights alike across it).
    std::vector<Vec3d> normal_points = SurfacePoints(sub, frame, sub_depth);
    {
      Vec3d x_mean = Vec3d::Zero(), n_mean = Vec3d::Zero();
      for (std::size_t i = 0; i < starts.size(); ++i) {
        x_mean += normal_points[i];
        n_mean += starts[i];
      }
      x_mean /= static_cast<double>(starts.size());
      n_mean /= static_cast<double>(starts.size());
      double along = 0, spread = 0;
      for (std::size_t i = 0; i < starts.size(); ++i) {
        along += (normal_points[i] - x_mean).dot(starts[i] - n_mean);
        spread += (starts[i] - n_mean).squaredNorm();
      }
      const double scale = spread > 1e-9 * static_cast<double>(starts.size()) ? along / spread : 0;
      for (std::size_t i = 0; i < starts.size(); ++i) {
        normal_points[i] = x_mean + scale * (starts[i] - n_mean);
      }
    }
    // Each test: its model and settings, its costs at D = ∞, and the D it proposes.
    struct Test {
      solve::ModelCandidate model;
      solve::ModelChoiceSettings settings;
      std::vector<double> distant_costs, best_costs;  // at D = ∞ and at `distance`
      bool run = false, passes = false;
      double distance = 0, gain = 0, gain_error = 0;
    };
    Test tests[2];
    const auto test_costs = [&](Test& test, double d) {
      solve::ModelCandidate m = test.model;
      std::vector<double> c =
          std::isinf(d) ? solve::PixelHeldOutCosts(sub, m, sample, fold, test.settings)
                        : solve::PixelHeldOutCosts(NearData(sub, frame, sub_depth, centre, d), m,
                                                   sample, fold, test.settings);
      return std::pair(std::move(c), m);
    };
    for (const bool diffuse : {false, true}) {
      Test& test = tests[diffuse];
      test.model = PlanModel(plan);
      test.settings.fit = solve::internal::FitSettingsOf(plan.options);
      // The plan's weights by N·L were measured under distant lights: they weigh down the bands
      // where distant lights misfit, which a finite distance may be what explains. Every candidate
      // is fitted unweighted; the plan at the chosen distance measures its own.
      test.settings.fit.shading_weights = {};
      test.settings.sample = o.normals.model_sample;
      test.settings.threads = o.normals.threads;
      test.settings.starts = &starts;
      if (diffuse) {
        solve::MakeDiffuseTest(test.model, test.settings);
      } else if (test.model.lobe == reflectance::Lobe::kLambert) {
        continue;  // the same test as the diffuse one, less robust
      } else if (test.model.lobe == reflectance::Lobe::kNormalCentred) {
        // The foil (model_choice.h) is a brightening that follows the normal, which is what a
        // fall-off looks like from one pixel: chosen under distant lights it has taken the
        // fall-off in and would lose at any finite D, so it cannot judge one. The diffuse test
        // and the position check decide; at a D chosen the model is chosen again (warm) with
        // its lights, the foil among the candidates.
        continue;
      }
      test.run = true;
      const std::string criterion = diffuse ? "diffuse" : "model";
      std::vector<std::vector<double>> costs;
      const std::size_t first = result.scored.size();
      const auto score = [&](double d) {
        auto [c, m] = test_costs(test, d);
        costs.push_back(std::move(c));
        result.scored.push_back({d, m.heldout_cost, m.heldout_error, criterion});
        return m.heldout_cost;
      };
      const auto cost_of = [&](std::size_t i) { return result.scored[first + i].heldout_cost; };
      score(std::numeric_limits<double>::infinity());
      std::size_t best = 0;
      for (double f : kDistanceGrid) {
        score(f * result.object_size_px);
        if (cost_of(costs.size() - 1) < cost_of(best)) best = costs.size() - 1;
      }
      if (best > 0) {
        // Golden section in log D between the best grid point's neighbours.
        const std::size_t g = best - 1;  // its place in the grid
        const double step_lo = g > 0 ? kDistanceGrid[g - 1] : kDistanceGrid[0] / 1.5;
        const double step_hi =
            g + 1 < std::size(kDistanceGrid) ? kDistanceGrid[g + 1] : kDistanceGrid[g];
        GoldenSectionLog(step_lo * result.object_size_px, step_hi * result.object_size_px, 4,
                         score);
        for (std::size_t i = 1; i < costs.size(); ++i) {
          if (cost_of(i) < cost_of(best)) best = i;
        }
      }
      test.distant_costs = costs[0];
      test.best_costs = costs[best];
      const auto [mean, error] =
          solve::PairedDifference(costs[0].data(), costs[best].data(), costs[0].size());
      const double d = result.scored[first + best].distance_px;
      char line[240];
      std::snprintf(line, sizeof line,
                    "effective distance by the %s: best %.4g px (%.3g object sizes), held-out "
                    "gain %.4g +- %.2g over distant lights",
                    diffuse ? "diffuse term" : "object's model", d, d / result.object_size_px, mean,
                    error);
      say(line);
      test.distance = d;
      test.gain = mean;
      test.gain_error = error;
      test.passes = best > 0 && mean > error;  // a gain must exceed one standard error
    }
    // The diffuse test stands in for the object's model where a broad lobe imitates the fall-off;
    // where the object's own model predicts worse at its D beyond one standard error, its gain is
    // the Lambertian fit's misfit of the lobe's tails, not nearness (a noise-free Phong sphere
    // under 24 distant lights: diffuse gain 3.5 SE at 31 sizes, the model's loss 23 SE, and
    // every normal 0.8° off). The object's model is not asked the other way round: a Lambertian
    // fit of a glossy object is the misspecified one (DiLiGenT's ball: its lobe gains at
    // 3400 px, the Lambertian fit loses there, and the normals go 1.88° -> 1.13°).
    // A proposal stands only where the surface's points predict no worse than points placed by
    // their normals (PositionCheck), by both fits that ran, the more significant deciding: each
    // fit is wrong in its own way (a lobe chosen under distant lights may imitate the fall-off; a
    // Lambertian fit misses a lobe's tails), so neither vetoes alone. Distant renders with a GGX
    // lobe, which no Phong lobe takes, chose 7–11 object sizes by 2–14 standard errors, and their
    // normals went 0.7–1.4° → 2.1–2.7°: there the object's model prefers the normals' points by
    // 2.2–16 standard errors. A matte sphere under point lights at 1.5 object sizes: the diffuse
    // fit prefers the surface's by 20, its distant-chosen lobe the normals' by 1.9. On DiLiGenT
    // the more significant fit prefers the surface's points at every D proposed (1.4–5.0).
    const auto positions_explain = [&](double d, std::vector<double> surface_costs[2]) {
      const std::size_t first_check = result.position_checks.size();
      double decisive = 0;  // the more significant check's gain in standard errors
      for (int t = 0; t < 2; ++t) {
        Test& test = tests[t];
        if (!test.run) continue;
        if (surface_costs[t].empty()) surface_costs[t] = test_costs(test, d).first;
        const char* criterion = t ? "diffuse" : "model";
        const PhotometricData placed = NearData(sub, frame, sub_depth, centre, d, &normal_points);
        solve::ModelCandidate m = test.model;
        const std::vector<double> c =
            solve::PixelHeldOutCosts(placed, m, sample, fold, test.settings);
        result.scored.push_back(
            {d, m.heldout_cost, m.heldout_error, std::string(criterion) + ", placed by normals"});
        PositionCheck check;
        check.distance_px = d;
        check.criterion = criterion;
        std::tie(check.gain, check.gain_error) =
            solve::PairedDifference(c.data(), surface_costs[t].data(), c.size());
        result.position_checks.push_back(check);
        const double z = check.gain_error > 0 ? check.gain / check.gain_error
                                              : (check.gain > 0) - (check.gain < 0);
        if (std::abs(z) > std::abs(decisive)) decisive = z;
      }
      const bool refused = decisive < -1;
      for (std::size_t i = first_check; i < result.position_checks.size(); ++i) {
        PositionCheck& check = result.position_checks[i];
        check.refused = refused;
        char line[240];
        std::snprintf(line, sizeof line,
                      "the %s at %.4g px with points placed by their normals: held-out cost %.4g "
                      "+- %.2g %s than with the surface's",
                      check.criterion == "model" ? "object's model" : "diffuse term", d,
                      std::abs(check.gain), check.gain_error, check.gain < 0 ? "lower" : "higher");
        say(line);
      }
      if (refused) {
        char line[240];
        std::snprintf(line, sizeof line,
                      "%.4g px refused: points placed by their normals predict better by %.3g "
                      "standard errors, so the gain is the fit's shape, not nearness",
                      d, -decisive);
        say(line);
      }
      return !refused;
    };
    Test& model_test = tests[0];
    Test& diffuse_test = tests[1];
    if (model_test.run && model_test.passes) {
      std::vector<double> surface[2] = {model_test.best_costs, {}};
      model_test.passes = positions_explain(model_test.distance, surface);
    }
    if (diffuse_test.passes) {
      std::vector<double> surface[2] = {{}, diffuse_test.best_costs};
      if (model_test.run) {
        surface[0] = test_costs(model_test, diffuse_test.distance).first;
        const auto [loss, error] = solve::PairedDifference(
            surface[0].data(), model_test.distant_costs.data(), surface[0].size());
        result.model_loss = loss;
        result.model_loss_error = error;
        char line[200];
        std::snprintf(line, sizeof line,
                      "the object's model at %.4g px: held-out loss %.4g +- %.2g over distant "
                      "lights",
                      diffuse_test.distance, loss, error);
        say(line);
        if (loss > error) diffuse_test.passes = false;
      }
      if (diffuse_test.passes)
        diffuse_test.passes = positions_explain(diffuse_test.distance, surface);
    }
    double best_t = 0;
    for (int t = 0; t < 2; ++t) {
      const Test& test = tests[t];
      if (!test.run || !test.passes) continue;
      const double z = test.gain_error > 0 ? test.gain / test.gain_error : INFINITY;
      if (z <= best_t) continue;
      best_t = z;
      distance = test.distance;
      result.gain = test.gain;
      result.gain_error = test.gain_error;
      result.criterion = t ? "diffuse" : "model";
    }
  }
  result.choice_seconds = SecondsSince(choice_start);
  result.distance_px = distance;
  if (std::isinf(distance)) {
    finish_distant();
    result.seconds = SecondsSince(start);
    return result;
  }

  // The near passes: the model chosen again with these lights (warm), then every pixel refined
  // from its last normal, the surface integrated, until the normals settle. `near` holds the
  // lights and points; the observations stay with the capture.
  PhotometricData near = NearData(LayoutOf(data), frame, depth, centre, distance);
  std::vector<Vec3d> starts;
  {
    const std::vector<Vec3d> all = NormalsPerPixel(result.distant, data);
    for (std::size_t i : plan_sample) starts.push_back(all[i]);
  }
  // The model is chosen again (warm) with these lights, whichever test found the distance: a
  // lobe chosen with distant lights may have been imitating the fall-off the distance now
  // explains. Even where the object's model found D, its lobe still carried part of the fall-off
  // (a Lambertian sphere under a dome, directions only: 7.68° with the distant choice's Phong
  // lobe kept, 3.80° chosen again, its Lambert run 4.26°; DiLiGenT's ball 1.13° -> 1.12°).
  // A distance chosen from the images is the explanation of the fall-off across the object that
  // the unweighted fits above preferred; weights and offsets by N·L measured on top of it take
  // the same fall-off on a second time (a matte (N·L)^1.3 sphere under distant lights, read as
  // near: each alone is right, both together bend the normals). So at a chosen distance the fits
  // are not weighed by N·L; at a distance the user gave, the misfit left there is the object's.
  solve::NormalOptions near_options = o.normals;
  if (result.chosen) near_options.weigh_by_shading = false;
  const auto replan_start = Clock::now();
  solve::NormalPlan near_plan = plan;
  if (solve::NeedsPlanSample(o.normals)) {
    PhotometricData sample = std::move(capture.observations({plan_sample})[0]);
    sample.points_cam.clear();
    for (std::size_t i : plan_sample) sample.points_cam.push_back(near.points_cam[i]);
    WithLightsOf(sample, near);
    near_plan = solve::PlanNormals(sample, near_options, &starts);
  }  // else no model choice: the plan has no weights to drop
  {
    char line[200];
    std::snprintf(line, sizeof line, "model chosen again with these lights: %s %.3g%s, %.2f s",
                  reflectance::LobeName(near_plan.options.model).c_str(),
                  near_plan.options.shininess,
                  result.chosen && o.normals.weigh_by_shading ? " (not weighed by N.L)" : "",
                  SecondsSince(replan_start));
    say(line);
  }
  solve::NormalResult last = result.distant;
  for (int pass = 0; pass < o.max_passes; ++pass) {
    const auto pass_start = Clock::now();
    solve::NormalResult now = capture.refine(near, near_plan, last);
    NearPass record;
    record.kind = "refine";
    record.change_deg = MeanChangeDeg(last, now, near);
    depth = IntegratedDepth(now, near, frame, std::vector<double>(pixels, 0.0), o.min_cos,
                            o.normals.threads);
    near.points_cam = SurfacePoints(near, frame, depth);
    record.distance = distance;
    record.seconds = SecondsSince(pass_start);
    result.passes.push_back(record);
    last = std::move(now);
    char line[160];
    std::snprintf(line, sizeof line, "near pass %d: normals moved %.3f deg, %.2f s", pass + 1,
                  record.change_deg, record.seconds);
    say(line);
    if (record.change_deg < o.tolerance_deg) break;
  }
  if (solve::NeedsPlanSample(o.normals)) {
    std::vector<Vec3f> sample_ks;
    solve::AppendSampleSpecular(last, near, plan_sample, sample_ks);
    solve::FinishNormals(last, near_plan, sample_ks);
  }
  result.normals = std::move(last);
  result.height = ImageF(data.width, data.height, 1, NAN);
  for (std::size_t i = 0; i < pixels; ++i) {
    result.height.pixels[static_cast<std::size_t>(data.pixels[i])] = static_cast<float>(-depth[i]);
  }
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace iphong::near
