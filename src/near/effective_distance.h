// Captures that give light directions only (DiLiGenT, UW, an RTI .lp) may still be near:
// DiLiGenT's LEDs sit about a metre from 11 cm objects. One effective distance D puts every light
// at S_j = c + D·L_j round the centre c the directions were measured from (orthographic view,
// heights in pixels: D in pixels), with the intensity it has at c (Φ_j = E_j·D², isotropic), and
// the near-light loop (near.h) runs with those lights. c is the object's centre: behind the
// visible surface's centroid by a depth δ chosen with D (a sphere's centroid is two thirds of its
// radius in front of its centre; read from the centroid, a dome at 1.5 object sizes made the
// normals 6.7° off at the true D; from the centre, 0.3° on a near-orthographic copy).
//
// D and δ are chosen by what predicts held-out lights best: the distant solve first (the plan,
// the search, every pixel's fit), its normals integrated into a surface, then each candidate —
// D = ∞ (distant), and the object's size times 1.5, 2, 3, 4, 6, … 32 with the centre at the
// centroid and at the depth of the surface's rim — scored by held-out costs on the model
// choice's pixels and folds (solve::PixelHeldOutCosts), each fold's normal refined from the
// distant one with those lights (warm: no search), by two tests: the plan's model (a sharp lobe
// places highlights by each pixel's light directions) and a Lambertian fit with highlights
// censored (the diffuse fall-off, which a broad lobe can imitate). In each the lowest grid point
// is refined: by a simplex search in (log D, δ) where the two depths' costs differ by more than
// their paired standard error, else in log D by golden section with the centre at the rim. D = ∞
// is kept unless one of them predicts better by more than one paired standard error (the more
// significant one is tried first): a truly distant capture is left as it is. A proposed D stands
// only where, on the surface it makes (every pixel refined under its lights and integrated), the
// surface's points predict better than points placed by their normals (PositionCheck): near
// lights act by where points are, a fit's misfit by which way they face.
// With a finite D the model is chosen again (warm) with its lights: the surface the standing
// proposal made with it is the first pass (the model chosen once more where that pass moved the
// lights), and the loop refines every pixel from its last normal, integrating and refining until
// the normals or the lights settle. At D = ∞
// (chosen or given) with the foil kept, every pixel is refitted with the foil from its distant
// normal, the per-pixel test's choice undone (foil_refit).
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "near/near.h"
#include "solve/bands.h"

namespace iphong::near {

struct DistanceCandidate {
  double distance_px = std::numeric_limits<double>::infinity();
  double centre_behind_px = 0;  // the lights' centre: this far behind the surface's centroid
  double heldout_cost = 0;      // mean per pixel, in units of each pixel's t²
  double heldout_error = 0;     // its standard error
  // "model" (the plan's) or "diffuse" (Lambert, highlights censored); the position checks' and
  // the rounds' candidates say so after a comma ("model, again on the near surface").
  std::string criterion;
};

// Nearness is a property of where the surface's points are. At the distance a test proposes,
// every pixel is refined under its lights from its distant normal (the object's model, Lambert
// where the plan has the foil) and integrated; on that surface the same lights are also set
// round points made from the normals alone: the least-squares fit X ≈ a + s·N of the surface's
// points over the sample (on a sphere the surface itself, so there the check ties by
// construction and decides on small consistent differences). The
// fall-off of near lights depends on where points are; a gain made of a fit's misfit — a lobe's
// tails a Phong lobe cannot take, a diffuse term of another shape — depends on which way they
// face, and points placed by their normals predict it as well or better. Both fits that ran are
// compared at the proposed D and the more significant decides: refused where it has the normals'
// points predicting better beyond one paired standard error.
struct PositionCheck {
  double distance_px = 0;
  std::string criterion;  // the fit compared: "model" (the object's) or "diffuse"
  // Held-out cost (t² per pixel) with the points placed by their normals less with the surface's
  // own, and its paired standard error: positive where the positions explain the gain.
  double gain = 0;
  double gain_error = 0;
  bool refused = false;  // the proposal at distance_px refused (the same for both fits' checks)
};

struct EffectiveDistanceOptions {
  solve::NormalOptions normals;
  // > 0: this D (pixels) instead of choosing one; infinity: the distant solve alone.
  double distance_px = 0;
  // Near passes after the distant solve, until the normals' mean change is under tolerance_deg,
  // or the lights as the new surface's points see them have moved by less than that
  // (internal::LightsMovedDeg): the next pass would refit every pixel under the lights it has
  // already been fitted under, to within the tolerance. A tenth of a degree is under any
  // photograph's accuracy (docs/guides/near-lights.md: how many passes captures take).
  int max_passes = 3;
  double tolerance_deg = 0.1;
  // A chosen D and its centre are chosen again this many times at most on the surface the
  // passes made (internal::RefineDistance: the first choice, on the distant solve's surface,
  // sets the lights too far), each followed by passes under the new lights; they stop once the
  // new D moves the lights by less than tolerance_deg. 0: the first choice stands.
  int distance_rounds = 1;
  double min_cos = 0.05;  // integration's grazing guard
  std::function<void(const std::string&)> log;

  std::string Validate() const;
};

struct EffectiveDistanceResult {
  solve::NormalResult normals;  // the chosen D's (the distant solve's for D = ∞)
  solve::NormalResult distant;  // the distant solve's
  double distance_px = std::numeric_limits<double>::infinity();
  double object_size_px = 0;  // the larger side of the mask's bounding box
  // The lights' centre c: this far behind the distant surface's centroid, along the view (0 at
  // D = ∞); and how far that surface's rim (its heights' 1st percentile) is behind the centroid.
  double centre_behind_px = 0;
  double relief_px = 0;
  std::vector<DistanceCandidate> scored;  // D = ∞ first, the grid, the refinement, the rounds
  // Held-out cost at D = ∞ less at the D first chosen (t² per pixel) and its paired standard
  // error, by the test that chose it ("model" or "diffuse"; "" for D = ∞); a round's gain over
  // that D is in `scored` ("…, again on the near surface").
  double gain = 0, gain_error = 0;
  std::string criterion;
  // Where the diffuse test proposed a D: the object's model's held-out loss there over D = ∞ and
  // its standard error (the D is refused when the loss exceeds it); NaN when not asked.
  double model_loss = std::numeric_limits<double>::quiet_NaN();
  double model_loss_error = std::numeric_limits<double>::quiet_NaN();
  // Every proposal's PositionCheck, in the order made (the diffuse test's D checked with the
  // object's model too).
  std::vector<PositionCheck> position_checks;
  bool chosen = false;  // false: given (distance_px), not chosen
  // D = ∞ with the foil: `normals` is the distant solve refitted with the foil at every pixel, the
  // per-pixel test's choice undone (ContinueEffectiveDistance says why).
  bool foil_refit = false;
  std::vector<NearPass> passes;
  ImageF height;  // 1 channel: the last surface's heights in pixels (NaN outside), finite D only
  double distant_seconds = 0, choice_seconds = 0, seconds = 0;
};

// Throws std::invalid_argument for invalid data or options. Data with point lights is refused:
// their positions are known (near.h).
EffectiveDistanceResult SolveEffectiveDistance(const solve::PhotometricData& data,
                                               const EffectiveDistanceOptions& options);

// The same on a capture read in bands of rows (solve/bands.h), for captures whose observations do
// not fit in memory: the distant solve in bands, then the choice and every near pass as above,
// each pass reading the bands again; only per-pixel results (the normal maps, the surface) are
// whole. Every step is per pixel or on the same samples, so the result is the in-memory one bit
// for bit, whatever the band height.
EffectiveDistanceResult SolveEffectiveDistanceInBands(const solve::BandSource& source,
                                                      int band_rows,
                                                      const EffectiveDistanceOptions& options,
                                                      const solve::BandProgress& progress = {});
// Memory the whole-field part needs per masked pixel, beside the bands themselves: the results
// of two passes (11 floats each), the depth, the surface point, the pixel index, and the
// integration (its multigrid conjugate gradient reports about 160 bytes a pixel).
constexpr double kEffectiveDistanceBytesPerPixel = 2 * 11 * 4 + 8 + 24 + 4 + 160;

// What the choice of D and the near passes read of a capture, held whole or in bands.
struct DistanceCapture {
  // Size, masked pixels (row-major) and lights; its observations are not read.
  const solve::PhotometricData* layout = nullptr;
  // The observations of the pixels at each list of positions (ascending, in masked order).
  std::function<std::vector<solve::PhotometricData>(const std::vector<std::vector<std::size_t>>&)>
      observations;
  // Every pixel refitted from `previous` (solve::RefineNormalsWithPlan) under near_layout's point
  // lights and surface points (its observations empty).
  std::function<solve::NormalResult(const solve::PhotometricData& near_layout,
                                    const solve::NormalPlan& plan,
                                    const solve::NormalResult& previous)>
      refine;
};
// The part after the distant solve (`distant`, finished with `plan`): the surface, D, the passes.
EffectiveDistanceResult ContinueEffectiveDistance(const DistanceCapture& capture,
                                                  const solve::NormalPlan& plan,
                                                  solve::NormalResult distant,
                                                  const EffectiveDistanceOptions& options);

}  // namespace iphong::near
