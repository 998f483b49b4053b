#include "near/near.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include "core/parallel.h"
#include "core/timing.h"
#include "geometry/height_map.h"
#include "near/internal.h"
#include "reflectance/material.h"
#include "solve/assemble.h"
#include "solve/model_choice.h"
#include "solve/pixel_fit.h"
#include "solve/shading_weights.h"

namespace iphong::near {

using solve::PhotometricData;
using namespace internal;

namespace {

// Woodham's passes: more while its normals still move by this much, up to this many.
constexpr double kSettledDeg = 0.2;
constexpr int kMaxWoodhamPasses = 6;

}  // namespace

std::string NearOptions::Validate() const {
  if (auto m = normals.Validate(); !m.empty()) return m;
  if (!(distance == 0 || geometry::ScaleInRange(distance))) {
    return "distance must be 0 (from the lights' layout) or between 1e-12 and 1e12 mm";
  }
  if (max_passes < 1 || max_passes > 100) return "passes must be in 1..100";
  if (woodham_passes < 0 || woodham_passes > 100) return "woodham passes must be in 0..100";
  if (!(tolerance_deg > 0) || !std::isfinite(tolerance_deg)) return "tolerance must be > 0";
  if (!(min_cos > 0 && min_cos < 1)) return "min_cos must be in (0, 1)";
  if (scale_sample < 10) return "scale sample must be >= 10";
  if (!(distance_range >= 1) || std::isnan(distance_range)) return "distance range must be >= 1";
  return "";
}

namespace {

// The loop of near.h on one capture: its data (surface points moved as the loop goes), frame,
// options and the sample whose fits place the surface.
class Loop {
 public:
  Loop(PhotometricData data, const geometry::HeightMapFrame& frame, const NearOptions& o)
      : data_(std::move(data)), frame_(frame), o_(o) {
    data_.perspective = frame.perspective;
    sample_ = solve::SpreadIndices(data_.pixel_count(),
                                   std::min<int>(o.scale_sample, int(data_.pixel_count())));
    woodham_ = o.normals;
    woodham_.model = reflectance::Lobe::kLambert;
    woodham_.material_known = false;
    // Before the object's lobe is known the surface is placed by Lambertian fits that leave
    // highlights out as they leave shadows out (as Woodham drops the brightest tenth).
    lambert_fit_ = solve::internal::FitSettingsOf(woodham_);
    lambert_fit_.model.lobe = reflectance::Lobe::kLambert;
    lambert_fit_.censor_bright = true;
  }

  void Say(const std::string& line) const {
    if (o_.log) o_.log(line);
  }

  // The ambient term the surface is placed with while the model is not chosen yet (the plan
  // then chooses its own with the lobe): the estimate (solve::EstimateAmbient) or none, whichever
  // fits the images better at the current surface. A constant left in the observations is
  // explained by the fall-off of lights at a wrong distance (a dome's sphere went from 464 to
  // 212 mm under an ambient of 1 % of its brightness).
  void ChooseAmbient() {
    if (o_.normals.material_known || !o_.normals.ambient_term.isZero()) return;
    const Vec3d ambient = solve::EstimateAmbient(data_);
    if (ambient.isZero()) return;
    double best = INFINITY;
    Vec3d chosen = Vec3d::Zero();
    for (const Vec3d& reading : {Vec3d(Vec3d::Zero()), ambient}) {
      woodham_.ambient_term = reading;
      lambert_fit_.ambient_term = reading;
      const solve::NormalResult w = solve::EstimateNormals(data_, woodham_);
      const double c = SurfaceCost(data_, frame_, depth_, NormalsPerPixel(w, data_), sample_,
                                   lambert_fit_, o_.normals.threads);
      if (c < best) best = c, chosen = reading;
    }
    woodham_.ambient_term = chosen;
    lambert_fit_.ambient_term = chosen;
  }

  void Place(const std::vector<double>& depth) {
    depth_ = depth;
    data_.points_cam = SurfacePoints(data_, frame_, depth_);
    solve::SetReferenceLights(data_, solve::MeanPoint(data_));
  }

  // Woodham's normals at the current surface, the surface they integrate to (its free number from
  // the current one) and that surface's misfit.
  double WoodhamSurface(std::vector<Vec3d>* normals = nullptr) {
    const solve::NormalResult w = solve::EstimateNormals(data_, woodham_);
    const std::vector<Vec3d> n = NormalsPerPixel(w, data_);
    Place(IntegratedDepth(w, data_, frame_, depth_, o_.min_cos, o_.normals.threads));
    if (normals) *normals = n;
    return SurfaceCost(data_, frame_, depth_, n, sample_, lambert_fit_, o_.normals.threads);
  }

  // Starts for the loop when nothing says where the object is: the surfaces of a grid of
  // distances (factors of √2 up to 16 either way of `distance`), each local minimum of their
  // misfit refined by two rounds of Woodham, integration and the surface's distance; by misfit.
  std::vector<std::pair<double, std::vector<double>>> Scan(double distance) {
    std::vector<std::pair<double, std::vector<double>>> grid, minima;
    Place(std::vector<double>(data_.pixel_count(), distance));
    ChooseAmbient();
    // Factors of √2: a ring's true distance can be a minimum narrower than a factor of 2 (a
    // ring of 300 mm round the lens, the object at 466 mm: the grid at 300 and 600 both fit worse
    // than a false minimum at 190).
    for (int i = -8; i <= 8; ++i) {
      Place(std::vector<double>(data_.pixel_count(), distance * std::pow(2.0, 0.5 * i)));
      const double c = WoodhamSurface();
      grid.emplace_back(c, depth_);
    }
    for (std::size_t i = 0; i < grid.size(); ++i) {
      const bool minimum = (i == 0 || grid[i].first <= grid[i - 1].first) &&
                           (i + 1 == grid.size() || grid[i].first <= grid[i + 1].first);
      if (!minimum) continue;
      Place(grid[i].second);
      double c = grid[i].first;
      // Rounds of Woodham, integration and the surface's distance until the normals settle: a
      // start's misfit is compared only once its surface is its own (a ring's true distance
      // misfit 0.053 after two rounds against a false one's 0.019, and 0 settled).
      std::vector<Vec3d> last;
      for (int round = 0; round < kMaxWoodhamPasses; ++round) {
        std::vector<Vec3d> normals;
        WoodhamSurface(&normals);
        const double f = ChooseSurfaceOffset(data_, frame_, depth_, normals, sample_, lambert_fit_,
                                             std::sqrt(2.0), o_.normals.threads);
        Place(WithFactor(depth_, f, frame_.perspective));
        c = SurfaceCost(data_, frame_, depth_, normals, sample_, lambert_fit_, o_.normals.threads);
        double moved = 0;
        for (std::size_t n = 0; n < normals.size() && !last.empty(); ++n) {
          moved += std::acos(std::clamp(normals[n].dot(last[n]), -1.0, 1.0));
        }
        moved *= 180 / M_PI / std::max<std::size_t>(1, normals.size());
        if (!last.empty() && moved < kSettledDeg) break;
        last = std::move(normals);
      }
      minima.emplace_back(c, depth_);
    }
    std::sort(minima.begin(), minima.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    return minima;
  }

  // The passes of near.h from the surface `depth`; `cost` receives the final surface's misfit
  // under the model the run chose.
  // `warm_plan`: the model is chosen from the last Woodham pass's normals (solve::PlanNormals
  // with starts) instead of searching: a start only compared with another.
  // The surface's mean distance is kept within [min_distance, max_distance].
  NearResult Run(const std::vector<double>& depth, double* cost, bool warm_plan = false,
                 double min_distance = 0,
                 double max_distance = std::numeric_limits<double>::infinity()) {
    Place(depth);
    ChooseAmbient();
    const std::size_t pixels = data_.pixel_count();
    NearResult result;
    int woodham_passes = o_.woodham_passes;
    std::optional<solve::NormalPlan> plan;
    bool replanned = false;
    int refines = 0;
    solve::NormalResult last;
    solve::PixelFitSettings fit = lambert_fit_;
    for (int pass = 0; pass < woodham_passes + o_.max_passes; ++pass) {
      const auto pass_start = Clock::now();
      NearPass record;
      solve::NormalResult now;
      if (pass < woodham_passes) {
        record.kind = "woodham";
        now = solve::EstimateNormals(data_, woodham_);
      } else if (!plan) {
        record.kind = "solve";
        const std::vector<std::size_t> plan_sample =
            solve::PlanSampleIndices(pixels, o_.normals.plan_sample);
        std::vector<Vec3d> starts;
        if (warm_plan && pass > 0) {
          const std::vector<Vec3d> all = NormalsPerPixel(last, data_);
          for (std::size_t i : plan_sample) starts.push_back(all[i]);
        }
        plan = solve::PlanNormals(
            plan_sample.size() == pixels ? data_ : solve::SubsetObservations(data_, plan_sample),
            o_.normals, starts.empty() ? nullptr : &starts);
        now = solve::SolveNormalsWithPlan(data_, *plan);
        std::vector<Vec3f> sample_ks;
        solve::AppendSampleSpecular(now, data_, plan_sample, sample_ks);
        solve::FinishNormals(now, *plan, sample_ks);
        // A Lambertian plan keeps the fits that leave highlights out, as Woodham does.
        if (plan->options.model != reflectance::Lobe::kLambert) {
          fit = solve::internal::PlanFitSettings(*plan);
        }
      } else {
        record.kind = "refine";
        now = solve::RefineNormalsWithPlan(data_, *plan, last);
      }
      record.change_deg = pass == 0 ? 0.0 : MeanChangeDeg(last, now, data_);
      // The surface these normals make, at the distance their own fits choose.
      const std::vector<Vec3d> normals = NormalsPerPixel(now, data_);
      const std::vector<double> shape =
          IntegratedDepth(now, data_, frame_, depth_, o_.min_cos, o_.normals.threads);
      const double f = ChooseSurfaceOffset(data_, frame_, shape, normals, sample_, fit, 2,
                                           o_.normals.threads, min_distance, max_distance);
      Place(WithFactor(shape, f, frame_.perspective));
      record.distance = Mean(depth_);
      record.seconds = SecondsSince(pass_start);
      result.passes.push_back(record);
      char line[200];
      std::snprintf(line, sizeof line,
                    "pass %d (%s): normals moved %.3f deg, distance %.4g, %.2f s", pass + 1,
                    record.kind.c_str(), record.change_deg, record.distance, record.seconds);
      Say(line);
      last = std::move(now);
      result.last_change_deg = record.change_deg;
      // A loop whose normals stopped settling (the surface's distance trading a fraction of a
      // percent back and forth) is done too, though not below the tolerance.
      const bool stalled =
          record.kind == "refine" && refines >= 3 &&
          record.change_deg >= 0.9 * result.passes[result.passes.size() - 2].change_deg;
      if (record.kind == "refine") ++refines;
      if (record.kind == "refine" && (record.change_deg < o_.tolerance_deg || stalled)) {
        // The model was chosen on the surface Woodham's normals gave; chosen again (warm: from
        // these normals) on the settled surface, and refined further if it changed.
        if (!replanned && solve::NeedsPlanSample(o_.normals)) {
          replanned = true;
          const auto replan_start = Clock::now();
          const std::vector<std::size_t> plan_sample =
              solve::PlanSampleIndices(pixels, o_.normals.plan_sample);
          const std::vector<Vec3d> all = NormalsPerPixel(last, data_);
          std::vector<Vec3d> starts;
          for (std::size_t i : plan_sample) starts.push_back(all[i]);
          solve::NormalPlan again = solve::PlanNormals(
              solve::SubsetObservations(data_, plan_sample), o_.normals, &starts);
          const solve::ModelCandidate& a = plan->model_choice.chosen;
          const solve::ModelCandidate& b = again.model_choice.chosen;
          // Only the lobe is asked again: it is what a surface a little off can bend (a lobe
          // that imitates the wrong lights' fall-off). The rest — the ks prior, the ambient term,
          // the codes' reading — is the first plan's unless the lobe changed.
          const bool same =
              a.lobe == b.lobe && std::abs(std::log(a.shininess / b.shininess)) < 0.05;
          char note[200];
          std::snprintf(note, sizeof note,
                        "model chosen again on the settled surface: %s %.3g (was %s %.3g), %.2f s",
                        reflectance::LobeName(b.lobe).c_str(), b.shininess,
                        reflectance::LobeName(a.lobe).c_str(), a.shininess,
                        SecondsSince(replan_start));
          Say(note);
          if (!same) {
            plan = std::move(again);
            if (plan->options.model != reflectance::Lobe::kLambert) {
              fit = solve::internal::PlanFitSettings(*plan);
            } else {
              fit = lambert_fit_;
            }
            refines = 0;
            continue;
          }
          // The weights and offsets by N·L, though, measured the misfit of the first surface's
          // lights as well as the object's: measured again on the settled surface, they are taken
          // when they moved (an exact Lambertian dome's bands are biased on the first surface,
          // unbiased on the settled one).
          if (!solve::SameShading(plan->options.shading_weights, again.options.shading_weights)) {
            plan->options.shading_weights = again.options.shading_weights;
            plan->model_choice.shading = again.model_choice.shading;
            if (plan->options.model != reflectance::Lobe::kLambert) {
              fit = solve::internal::PlanFitSettings(*plan);
            }
            Say("weights by N.L measured again on the settled surface");
            refines = 0;
            continue;
          }
        }
        result.converged = !stalled;
        break;
      }
      // Woodham's passes go on while the surface still moves (each costs little), so the model
      // is chosen on the surface Woodham's normals settle on.
      if (record.kind == "woodham" && pass + 1 == woodham_passes &&
          (pass == 0 || record.change_deg > kSettledDeg) && woodham_passes < kMaxWoodhamPasses) {
        ++woodham_passes;
      }
    }
    if (plan) {
      // The whole-object summaries (the object's ks, the notes) of the final pass's pixels.
      const std::vector<std::size_t> plan_sample =
          solve::PlanSampleIndices(pixels, o_.normals.plan_sample);
      std::vector<Vec3f> sample_ks;
      solve::AppendSampleSpecular(last, data_, plan_sample, sample_ks);
      solve::FinishNormals(last, *plan, sample_ks);
    }
    if (cost) {
      *cost = SurfaceCost(data_, frame_, depth_, NormalsPerPixel(last, data_), sample_, fit,
                          o_.normals.threads);
    }
    result.normals = std::move(last);
    result.distance = Mean(depth_);
    result.depth = ImageF(data_.width, data_.height, 1);
    result.points = ImageF(data_.width, data_.height, 3);
    for (std::size_t i = 0; i < pixels; ++i) {
      const std::size_t p = static_cast<std::size_t>(data_.pixels[i]);
      result.depth.pixels[p] = static_cast<float>(DepthOf(data_.points_cam[i]));
      for (int c = 0; c < 3; ++c) {
        result.points.pixels[3 * p + c] = static_cast<float>(data_.points_cam[i][c]);
      }
    }
    return result;
  }

 private:
  PhotometricData data_;
  geometry::HeightMapFrame frame_;
  const NearOptions& o_;
  std::vector<std::size_t> sample_;
  solve::NormalOptions woodham_;
  solve::PixelFitSettings lambert_fit_;
  std::vector<double> depth_;
};

// Two starts whose misfits are within this factor are both run to the end: a ring of lights
// leaves the distance weakly determined, and before the lobe is known a shiny object's misfit
// is mostly its highlights, left out alike at either distance.
constexpr double kAmbiguousStarts = 1.25;

}  // namespace

NearResult SolveNearLights(PhotometricData data, const geometry::HeightMapFrame& frame,
                           const NearOptions& o) {
  const auto start = Clock::now();
  if (auto m = o.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = frame.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (!data.near()) throw std::invalid_argument("near-light solve without point lights");
  if (data.pixel_count() == 0) throw std::invalid_argument("no pixel to solve");
  const std::size_t pixels = data.pixel_count();
  const double guess = o.distance > 0 ? o.distance : GuessDistance(data.point_lights);
  std::vector<double> far;
  for (const reflectance::Light& l : data.point_lights) far.push_back(l.position_cam.norm());
  std::nth_element(far.begin(), far.begin() + far.size() / 2, far.end());
  const double lights_distance = std::max(far[far.size() / 2], 1e-6);
  Loop loop(std::move(data), frame, o);
  NearResult result;
  if (guess > 0) {
    // A distance the user gives bounds the surface's to distance_range; the layout's (where the
    // LEDs point, a dome's centre) is the object's centre, nearer than its visible surface by up
    // to its radius, which near lights make a large fraction (a dome's centre 145 mm away, the
    // surface's mean 110 mm): a factor of 2.
    const double range = o.distance > 0 ? o.distance_range : 2.0;
    result =
        loop.Run(std::vector<double>(pixels, guess), nullptr, false, guess / range, guess * range);
  } else {
    // Nothing in the lights' layout says where the object is (a ring of lights in one plane):
    // the images say, from around the lights' own median distance from the camera.
    const auto starts = loop.Scan(lights_distance);
    char line[200];
    for (const auto& [cost, depth] : starts) {
      std::snprintf(line, sizeof line, "start at distance %.4g: misfit %.4g", Mean(depth), cost);
      loop.Say(line);
    }
    // Another start about as good is run too, its model chosen from its own Woodham normals
    // (warm: the search of the hemisphere is what the first run's choice costs). Each run keeps
    // its surface within distance_range of its start, so two basins stay two answers; when both
    // fit alike, the images do not tell the distance and the result says so.
    double best_cost = INFINITY;
    std::vector<std::pair<double, double>> runs;  // (misfit, distance)
    for (std::size_t i = 0; i < starts.size(); ++i) {
      if (i > 0 && !(starts[i].first <= kAmbiguousStarts * starts[0].first)) break;
      double cost = 0;
      const double from = Mean(starts[i].second);
      NearResult r = loop.Run(starts[i].second, &cost, i > 0, from / o.distance_range,
                              from * o.distance_range);
      std::snprintf(line, sizeof line, "from distance %.4g: %.4g, misfit %.4g", from, r.distance,
                    cost);
      loop.Say(line);
      runs.emplace_back(cost, r.distance);
      if (cost < best_cost) best_cost = cost, result = std::move(r);
    }
    for (const auto& [cost, d] : runs) {
      if (cost <= kAmbiguousStarts * best_cost &&
          std::abs(std::log(d / result.distance)) > std::log(o.distance_range)) {
        result.other_distances.push_back(d);
      }
    }
    result.distance_from_images = true;
  }
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace iphong::near
