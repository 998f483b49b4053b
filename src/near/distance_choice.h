// The choice of the effective distance (effective_distance.h): held-out tests of nearness over D
// and the depth of the lights' centre, and the position check a proposal must pass. Internal to
// near/; effective_distance.h states the model, the frame and why.
#pragma once

#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "geometry/height_map.h"
#include "near/effective_distance.h"
#include "near/near.h"
#include "solve/model_choice.h"

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

// Candidates for D, in the object's sizes (the mask's larger side): far enough apart that the
// grid's neighbours bracket the best, from 1.5 sizes (a dome round a large object) to 32. Beyond
// that a light's direction turns by under 1.8° across the object and its irradiance changes by
// under ±6 %, under what a photograph's normals are good to: there the held-out tests' "gains"
// were model misfit, not nearness (a distant render with an ambient term chose 92 object sizes by
// 0.3 % of its cost, beyond three standard errors). The refinement goes down to one size, where
// a light is half a size from the surface of the object round its centre.
inline constexpr double kDistanceGrid[] = {1.5, 2, 3, 4, 6, 8, 12, 16, 24, 32};
inline constexpr double kNearestSizes = 1.0;
// How far behind the surface's centroid the centre may be, in depths of its rim below the
// centroid: a sphere's centre is at its rim's depth, and the rim of a surface integrated from
// distant normals came out up to 30 % shallower than it is (a dome at 1.5 object sizes).
inline constexpr double kDeepestRims = 2.0;

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

// The held-out model of a plan: the chosen one, or what it was given (Lambert, known
// coefficients).
solve::ModelCandidate PlanModel(const solve::NormalPlan& plan);

// A test of nearness: the plan's model (Lambert's with highlights censored where `diffuse`,
// solve::MakeDiffuseTest) and the held-out settings it is scored with, unweighted, each fold's
// normal refined from `starts` (one per pixel of the sample).
std::pair<solve::ModelCandidate, solve::ModelChoiceSettings> DistanceTest(
    const solve::NormalPlan& plan, const EffectiveDistanceOptions& o, bool diffuse,
    const std::vector<Vec3d>* starts);

// Whether (ln D, the centre's depth) lies in the range the choice searches: 1–32 object sizes,
// the centre from the centroid down to kDeepestRims rims.
bool InDistanceRange(double log_d, double behind, double relief, double object_size_px);
// A Nelder–Mead simplex over (ln D, the centre's depth) from `simplex` (costs known), within that
// range, `score(D, behind)` giving each point's held-out cost.
void SearchDistanceAndCentre(std::vector<std::vector<double>> simplex, std::vector<double> costs,
                             double relief, double object_size_px,
                             const std::function<double(double, double)>& score);

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

// D and the centre's depth chosen again round (distance, behind) on a near pass's surface
// (`depth`, its normals `from`), by the test that chose them (the diffuse one with `diffuse`, else
// the object's model: `plan`'s, chosen under the pass's lights) on the model choice's pixels. The
// first choice was made on the surface the distant solve integrated, whose normals the near
// lights' fall-off bent, and the lights set round a bent surface are set too far (numpy spheres
// under a dome at 2.5 object sizes, directions only: D 567 px chosen for 350, then 406 on the
// first passes' surface). A simplex in (ln D, behind) from the first choice; the centre stays
// measured from `surface`'s centroid. Records each candidate in `result` (criterion "... on the
// near surface") and returns the best one scored where it predicts better than the start.
struct RefinedDistance {
  double distance = 0, behind = 0;
  // The start's held-out cost less the best's (t² per pixel) and its paired standard error; the
  // start is returned (moved false) unless the gain exceeds the error.
  double gain = 0, gain_error = 0;
  bool moved = false;
};
RefinedDistance RefineDistance(const DistanceCapture& capture, const solve::NormalPlan& plan,
                               const EffectiveDistanceOptions& o, const DistanceSurface& surface,
                               const std::vector<double>& depth, const solve::NormalResult& from,
                               bool diffuse, double distance, double behind,
                               EffectiveDistanceResult& result);

}  // namespace iphong::near::internal
