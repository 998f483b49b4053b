#include "near/effective_distance.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/timing.h"
#include "geometry/height_map.h"
#include "near/distance_choice.h"
#include "near/internal.h"
#include "reflectance/material.h"
#include "solve/assemble.h"
#include "solve/model_choice.h"

namespace iphong::near {
namespace {

using solve::PhotometricData;
using namespace internal;

}  // namespace

std::string EffectiveDistanceOptions::Validate() const {
  if (auto m = normals.Validate(); !m.empty()) return m;
  // A finite D beyond 1e12 px puts the lights' irradiance (1/D²) below double's sums: what is
  // meant is inf, which says so.
  if (!(distance_px == 0 || std::isinf(distance_px) || geometry::ScaleInRange(distance_px))) {
    return "distance must be 0 (choose), inf (distant) or between 1e-12 and 1e12 pixels";
  }
  if (max_passes < 1 || max_passes > 100) return "passes must be in 1..100";
  if (!(tolerance_deg > 0) || !std::isfinite(tolerance_deg)) return "tolerance must be > 0";
  if (distance_rounds < 0 || distance_rounds > 10) return "distance rounds must be in 0..10";
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
  DistanceSurface surface;  // orthographic, a pixel per unit
  const geometry::HeightMapFrame& frame = surface.frame;
  surface.depth = IntegratedDepth(result.distant, data, frame, std::vector<double>(pixels, 0.0),
                                  o.min_cos, o.normals.threads, kChoiceSurfacePixels);
  int col0 = data.width, col1 = 0, row0 = data.height, row1 = 0;
  for (int p : data.pixels) {
    col0 = std::min(col0, p % data.width), col1 = std::max(col1, p % data.width + 1);
    row0 = std::min(row0, p / data.width), row1 = std::max(row1, p / data.width + 1);
  }
  result.object_size_px = std::max(col1 - col0, row1 - row0);
  // The centre the directions were measured from is the object's, behind the part of it the
  // camera sees: the centroid of the visible surface lies in front of it (a sphere's by two
  // thirds of its radius, where the lights of a dome at 1.5 object sizes are 16–61 % brighter
  // than at its centre), and a flat object's centroid is its centre. How far behind is chosen
  // with D by the same held-out tests, between the centroid and kDeepestRims (distance_choice.cc)
  // times the depth of the surface's rim below it (`relief`).
  {
    Vec3d& centroid = surface.centroid;
    const std::vector<Vec3d> points = SurfacePoints(data, frame, surface.depth);
    std::vector<double> z;
    z.reserve(points.size());
    for (const Vec3d& x : points) centroid += x, z.push_back(x.z());
    centroid /= static_cast<double>(pixels);
    // The rim as the 1st percentile of the heights: one pixel's integration error is not a rim.
    auto rim = z.begin() + static_cast<std::ptrdiff_t>(z.size() / 100);
    std::nth_element(z.begin(), rim, z.end());
    surface.relief = std::max(0.0, centroid.z() - *rim);
  }
  DistanceChoice choice = ChooseDistance(capture, plan, o, surface, result);
  double distance = choice.distance, behind = choice.behind;
  std::optional<Proposed>& proposed = choice.proposed;
  result.choice_seconds = SecondsSince(choice_start);
  result.distance_px = distance;
  result.centre_behind_px = std::isinf(distance) ? 0.0 : behind;
  result.relief_px = surface.relief;
  if (std::isinf(distance)) {
    finish_distant();
    result.seconds = SecondsSince(start);
    return result;
  }

  // The near passes: the model chosen again with these lights (warm), then every pixel refined
  // from its last normal, the surface integrated, until the normals settle. `near` holds the
  // lights and points; the observations stay with the capture.
  // The model is chosen again whichever test found the distance: a lobe chosen with distant
  // lights may have been imitating the fall-off the distance now explains. Even where the
  // object's model found D, its lobe still carried part of the fall-off (a Lambertian sphere
  // under a dome, directions only: 7.68° with the distant choice's Phong lobe kept, 3.80° chosen
  // again, its Lambert run 4.26°; DiLiGenT's ball 1.13° -> 1.12°).
  // The surface the chosen proposal made with the model chosen so is the first pass (one made by
  // the diffuse test's Lambert, where the plan had the foil, is not the object's). Where that
  // pass moved the lights, the model is chosen once more under the lights of its surface, the
  // passes' own: the distant surface a near dome's lights were first set round is bent, and a
  // model chosen there carried it into every pass (numpy Phong spheres and ellipsoids under
  // domes at 1.5 object sizes: 0.2–0.4° worse).
  const bool from_proposal = proposed && proposed->distance == distance &&
                             proposed->behind == behind && proposed->plan.has_value();
  std::vector<double> depth = from_proposal ? std::move(proposed->depth) : std::move(surface.depth);
  PhotometricData near = NearData(LayoutOf(data), frame, depth, surface.CentreAt(behind), distance);
  solve::NormalResult last = from_proposal ? std::move(proposed->normals) : result.distant;
  const auto settled = [&](const NearPass& record) {
    char line[160];
    std::snprintf(line, sizeof line,
                  "near pass %zu: normals moved %.3f deg, lights %.3f deg, %.2f s",
                  result.passes.size(), record.change_deg, record.lights_moved_deg, record.seconds);
    say(line);
    // Settled, or the next pass would see the lights this one fitted under (the normals moved
    // because the model was chosen again, or the first pass left the distant lights).
    return record.change_deg < o.tolerance_deg || record.lights_moved_deg < o.tolerance_deg;
  };
  bool done = false;
  solve::NormalPlan near_plan;
  if (from_proposal) {
    result.passes.push_back(proposed->pass);
    done = settled(proposed->pass);
    near_plan = done || o.max_passes == 1
                    ? std::move(*proposed->plan)
                    : PlanAtLights(capture, plan, o, result.chosen, near, last, false);
  } else {
    near_plan = PlanAtLights(capture, plan, o, result.chosen, near, result.distant, false);
  }
  const auto passes = [&](std::size_t before) {
    while (!done && static_cast<int>(result.passes.size() - before) < o.max_passes) {
      const auto pass_start = Clock::now();
      solve::NormalResult now = capture.refine(near, near_plan, last);
      NearPass record;
      record.kind = "refine";
      record.change_deg = MeanChangeDeg(last, now, near);
      depth = IntegratedDepth(now, near, frame, std::vector<double>(pixels, 0.0), o.min_cos,
                              o.normals.threads);
      std::vector<Vec3d> points = SurfacePoints(near, frame, depth);
      record.lights_moved_deg = LightsMovedDeg(near, points);
      near.points_cam = std::move(points);
      record.distance = distance;
      record.seconds = SecondsSince(pass_start);
      result.passes.push_back(record);
      last = std::move(now);
      done = settled(record);
    }
  };
  passes(0);
  // D and the centre chosen again on the surface the passes made, and the passes again under
  // their lights, until the lights stay within the tolerance (RefineDistance says why).
  for (int round = 0; round < o.distance_rounds && result.chosen; ++round) {
    const RefinedDistance refined =
        RefineDistance(capture, near_plan, o, surface, depth, last, result.criterion == "diffuse",
                       distance, behind, result);
    if (!refined.moved) break;  // the first stands
    PhotometricData moved =
        NearData(LayoutOf(data), frame, depth, surface.CentreAt(refined.behind), refined.distance);
    const double change = LightsChangedDeg(near, moved);
    char line[200];
    std::snprintf(line, sizeof line,
                  "D %.4g px, the centre %.3g px behind: the lights move %.3f deg",
                  refined.distance, refined.behind, change);
    say(line);
    if (change < o.tolerance_deg) break;
    distance = refined.distance;
    behind = refined.behind;
    near = std::move(moved);
    near_plan = PlanAtLights(capture, plan, o, result.chosen, near, last, false);
    done = false;
    passes(result.passes.size());
  }
  result.distance_px = distance;
  result.centre_behind_px = behind;
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
