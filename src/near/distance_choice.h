// The choice of the effective distance (effective_distance.h): held-out tests of nearness over D
// and the depth of the lights' centre, and the position check a proposal must pass. Internal to
// near/; effective_distance.h states the model, the frame and why.
#pragma once

#include <optional>
#include <vector>

#include "geometry/height_map.h"
#include "near/effective_distance.h"
#include "near/near.h"

namespace iphong::near::internal {

// data's observations under point lights at c + D·L_j with the intensity they have at c, seen
// from the points of `depth` (orthographic, heights in pixels: depth = −height), or from
// `points` (one per pixel) where given.
solve::PhotometricData NearData(const solve::PhotometricData& data,
                                const geometry::HeightMapFrame& frame,
                                const std::vector<double>& depth, const Vec3d& centre,
                                double distance, const std::vector<Vec3d>* points = nullptr);
// data without its observations.
solve::PhotometricData LayoutOf(const solve::PhotometricData& data);
// `data`'s lights made `from`'s (point lights, the reference directions and intensities), and
// its points, when it holds every pixel `from` holds.
void WithLightsOf(solve::PhotometricData& data, const solve::PhotometricData& from);

// The distant solve's surface, orthographic with a pixel per unit (depth = −height, per masked
// pixel), its centroid and the depth of its rim below the centroid (`relief`, pixels).
struct DistanceSurface {
  geometry::HeightMapFrame frame;
  std::vector<double> depth;
  Vec3d centroid = Vec3d::Zero();
  double relief = 0;
  // The lights' centre `behind` pixels behind the centroid.
  Vec3d CentreAt(double behind) const {
    return Vec3d(centroid.x(), centroid.y(), centroid.z() - behind);
  }
};

// The surface a proposal makes — every pixel refined from its distant normal under the
// proposal's lights, integrated — on which the positions are checked. Made by the plan chosen
// again at those lights (`plan`), it is the first near pass, and the passes go on from it.
struct Proposed {
  double distance = 0, behind = 0;
  std::optional<solve::NormalPlan> plan;  // absent: made by the diffuse test's model (a foil plan)
  NearPass pass;                          // the refinement, as a near pass
  solve::NormalResult normals;
  std::vector<double> depth;
};

// The plan chosen again (warm: from `from`'s normals on the plan's sample) under the lights and
// points of `near` (every pixel of the capture); not weighed by N·L at a distance the images
// chose (effective_distance.cc says why). With `refit_starts`, the normals the choice starts from
// are first refitted by `plan` under those lights (`from` was fitted under other lights). Without
// a model to choose, the plan. Logs the choice.
solve::NormalPlan PlanAtLights(const DistanceCapture& capture, const solve::NormalPlan& plan,
                               const EffectiveDistanceOptions& o, bool chosen,
                               const solve::PhotometricData& near, const solve::NormalResult& from,
                               bool refit_starts);

struct DistanceChoice {
  double distance = 0;               // pixels; infinity: distant lights
  double behind = 0;                 // the centre's depth behind the centroid, pixels
  std::optional<Proposed> proposed;  // the last proposal whose surface was made, if any
};

// D (or, with o.distance_px > 0, the centre's depth at that D) by the held-out tests, each
// proposal checked on the surface it makes. Records the candidates, the checks and the gain in
// `result` and logs through o.log.
DistanceChoice ChooseDistance(const DistanceCapture& capture, const solve::NormalPlan& plan,
                              const EffectiveDistanceOptions& o, const DistanceSurface& surface,
                              EffectiveDistanceResult& result);

}  // namespace iphong::near::internal
