// The effective distance over a capture read in bands of rows (effective_distance.h).
#include <algorithm>
#include <stdexcept>

#include "core/timing.h"
#include "near/distance_choice.h"
#include "near/effective_distance.h"

namespace iphong::near {

EffectiveDistanceResult SolveEffectiveDistanceInBands(const solve::BandSource& source,
                                                      int band_rows,
                                                      const EffectiveDistanceOptions& o,
                                                      const solve::BandProgress& progress) {
  const auto start = Clock::now();
  if (auto m = o.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (band_rows < 1) throw std::invalid_argument("bands need at least one row each");
  const int width = source.width, height = source.height;

  // The distant solve in bands, its results pasted whole; the layout (pixels, lights) on the way.
  solve::PhotometricData layout;
  solve::NormalResult distant;
  solve::NormalPlan plan;
  const auto keep = [&](int y0, const solve::NormalResult& band) {
    solve::PasteResultRows(distant, band, y0, width, height);
  };
  solve::BandSource first = source;
  first.read = [&](int y0, int y1, bool first_pass) {
    solve::PhotometricData band = source.read(y0, y1, first_pass);
    if (layout.width == 0) {
      layout.width = width;
      layout.height = height;
      layout.images = band.images;
      layout.light_directions = band.light_directions;
      layout.light_intensities = band.light_intensities;
    }
    if (first_pass) {  // each band once: the first pass over the capture
      for (int p : band.pixels) layout.pixels.push_back(p + y0 * width);
    }
    return band;
  };
  solve::NormalResult total =
      solve::EstimateNormalsInBands(first, band_rows, o.normals, keep, progress, &plan);
  if (layout.pixels.empty()) throw std::invalid_argument("the mask selects no pixel");
  if (layout.images < 3) throw std::invalid_argument("an effective distance needs 3 images");
  {
    // The banded run's whole-object fields (ks, notes, summary) with the images pasted.
    solve::NormalResult whole = solve::ResultFields(total);
    whole.normals = std::move(distant.normals);
    whole.albedo = std::move(distant.albedo);
    whole.specular = std::move(distant.specular);
    whole.residual = std::move(distant.residual);
    whole.model_map = std::move(distant.model_map);
    distant = std::move(whole);
  }
  const double distant_seconds = SecondsSince(start);

  DistanceCapture capture;
  capture.layout = &layout;
  // A pass over the bands gathers every list's pixels at once.
  capture.observations = [&](const std::vector<std::vector<std::size_t>>& sets) {
    std::vector<solve::PhotometricData> out(sets.size());
    std::vector<std::size_t> next(sets.size(), 0);
    std::size_t position = 0;
    for (int y0 = 0; y0 < height; y0 += band_rows) {
      const int y1 = std::min(height, y0 + band_rows);
      const solve::PhotometricData band = source.read(y0, y1, false);
      for (std::size_t s = 0; s < sets.size(); ++s) {
        if (y0 == 0) out[s] = solve::SubsetObservations(band, {});
        std::vector<std::size_t> local;
        for (; next[s] < sets[s].size() && sets[s][next[s]] < position + band.pixel_count();
             ++next[s]) {
          local.push_back(sets[s][next[s]] - position);
        }
        solve::AppendObservations(out[s], band, local, std::size_t(y0) * width);
      }
      position += band.pixel_count();
    }
    for (solve::PhotometricData& d : out) d.width = width, d.height = height;
    return out;
  };
  // A pass over the bands refits each under the pass's lights, from the previous result's rows.
  int near_pass = 0;
  capture.refine = [&](const solve::PhotometricData& near_layout,
                       const solve::NormalPlan& near_plan, const solve::NormalResult& previous) {
    ++near_pass;
    solve::NormalResult now;
    std::size_t position = 0;
    for (int y0 = 0; y0 < height; y0 += band_rows) {
      const int y1 = std::min(height, y0 + band_rows);
      solve::PhotometricData band = source.read(y0, y1, false);
      internal::WithLightsOf(band, near_layout);
      if (!near_layout.points_cam.empty()) {  // empty: distant lights (the foil's refit)
        band.points_cam.assign(
            near_layout.points_cam.begin() + std::ptrdiff_t(position),
            near_layout.points_cam.begin() + std::ptrdiff_t(position + band.pixel_count()));
      }
      position += band.pixel_count();
      solve::NormalResult r =
          solve::RefineNormalsWithPlan(band, near_plan, solve::ResultRows(previous, y0, y1));
      if (y0 == 0) now = solve::ResultFields(r);
      solve::NormalSummary& s = now.summary;
      if (y0 > 0) {
        s.solve_seconds += r.summary.solve_seconds;
        s.iterations += r.summary.iterations;
        s.pixels += r.summary.pixels;
        s.dark_pixels += r.summary.dark_pixels;
        s.underdetermined_pixels += r.summary.underdetermined_pixels;
      }
      solve::PasteResultRows(now, r, y0, width, height);
      if (progress.rows) progress.rows(2 + near_pass, y1);
    }
    return now;
  };
  EffectiveDistanceResult result = ContinueEffectiveDistance(capture, plan, std::move(distant), o);
  result.distant_seconds = distant_seconds;
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace iphong::near
