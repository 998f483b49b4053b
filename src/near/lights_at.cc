// Observations and plans under a proposed set of near lights (distance_choice.h): the capture's
// data seen under point lights at a distance and centre, its layout, and the model chosen again
// under those lights. Shared by the distance choice and the near passes (effective_distance.cc).
#include <cstdio>
#include <string>
#include <vector>

#include "core/timing.h"
#include "near/distance_choice.h"
#include "near/internal.h"
#include "solve/assemble.h"
#include "solve/model_choice.h"

namespace iphong::near::internal {

using solve::PhotometricData;

// data's observations under point lights at c + D·L_j with the intensity they have at c, seen
// from the points of `depth` (orthographic, heights in pixels: depth = −height), or from
// `points` (one per pixel) where given.
PhotometricData NearData(const PhotometricData& data, const geometry::HeightMapFrame& frame,
                         const std::vector<double>& depth, const Vec3d& centre, double distance,
                         const std::vector<Vec3d>* points) {
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

solve::NormalPlan PlanAtLights(const DistanceCapture& capture, const solve::NormalPlan& plan,
                               const EffectiveDistanceOptions& o, bool chosen,
                               const PhotometricData& near, const solve::NormalResult& from,
                               bool refit_starts) {
  if (!solve::NeedsPlanSample(o.normals)) return plan;  // no model choice: no weights to drop
  const auto start = Clock::now();
  // A distance chosen from the images is the explanation of the fall-off across the object that
  // the unweighted fits of the choice preferred; weights and offsets by N·L measured on top of it
  // take the same fall-off on a second time (a matte (N·L)^1.3 sphere under distant lights, read
  // as near: each alone is right, both together bend the normals). So at a chosen distance the
  // fits are not weighed by N·L; at a distance the user gave, the misfit left there is the
  // object's.
  solve::NormalOptions options = o.normals;
  if (chosen) options.weigh_by_shading = false;
  const std::vector<std::size_t> plan_sample =
      solve::PlanSampleIndices(near.pixel_count(), o.normals.plan_sample);
  std::vector<Vec3d> starts;
  {
    const std::vector<Vec3d> all = NormalsPerPixel(from, near);
    for (std::size_t i : plan_sample) starts.push_back(all[i]);
  }
  PhotometricData sample = std::move(capture.observations({plan_sample})[0]);
  sample.points_cam.clear();
  for (std::size_t i : plan_sample) sample.points_cam.push_back(near.points_cam[i]);
  WithLightsOf(sample, near);
  if (refit_starts) {
    // Where the choice reads its starts (its spread sample), they are first refitted under these
    // lights by the plan: its held-out fits keep something of where they begin, and a normal
    // that distant lights bent is not where a pass under these lights begins (DiLiGenT pot1 on
    // 12 lights: from the distant normals 7.07°, refitted 6.82°).
    const std::vector<std::size_t> spread =
        solve::SpreadIndices(plan_sample.size(), o.normals.model_sample);
    const PhotometricData few = solve::SubsetObservations(sample, spread);  // its lights, points
    solve::NormalPlan by = plan;
    if (chosen) by.options.shading_weights = {};
    const std::vector<Vec3d> refitted =
        NormalsPerPixel(solve::RefineNormalsWithPlan(few, by, from), few);
    for (std::size_t k = 0; k < spread.size(); ++k) starts[spread[k]] = refitted[k];
  }
  solve::NormalPlan again = solve::PlanNormals(sample, options, &starts);
  if (o.log) {
    char line[200];
    std::snprintf(line, sizeof line, "model chosen again with these lights: %s %.3g%s, %.2f s",
                  reflectance::LobeName(again.options.model).c_str(), again.options.shininess,
                  chosen && o.normals.weigh_by_shading ? " (not weighed by N.L)" : "",
                  SecondsSince(start));
    o.log(line);
  }
  return again;
}

}  // namespace iphong::near::internal
