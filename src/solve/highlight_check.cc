#include "solve/highlight_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "integrate/frame_check.h"
#include "reflectance/material.h"

namespace iphong::solve {

namespace {

// The sample's pixels on a grid of `step` image pixels: per block of step × step, the sample's
// pixel nearest the block's top-left corner (exactly the corner when the sample holds every
// pixel), as a capture of its own whose pixel index is the block's; `mask` the blocks held.
PhotometricData Grid(const PhotometricData& sample, int max_side, int* step, Mask* mask) {
  int x0 = sample.width, y0 = sample.height, x1 = -1, y1 = -1;
  for (const int p : sample.pixels) {
    x0 = std::min(x0, p % sample.width), x1 = std::max(x1, p % sample.width);
    y0 = std::min(y0, p / sample.width), y1 = std::max(y1, p / sample.width);
  }
  const int side = std::max(x1 - x0 + 1, y1 - y0 + 1);
  *step = std::max(1, (side + max_side - 1) / max_side);
  const int gw = (x1 - x0) / *step + 1, gh = (y1 - y0) / *step + 1;
  std::vector<std::size_t> nearest(static_cast<std::size_t>(gw) * gh,
                                   std::numeric_limits<std::size_t>::max());
  std::vector<int> distance(nearest.size(), std::numeric_limits<int>::max());
  for (std::size_t i = 0; i < sample.pixel_count(); ++i) {
    const int x = sample.pixels[i] % sample.width - x0, y = sample.pixels[i] / sample.width - y0;
    const std::size_t b = static_cast<std::size_t>(y / *step) * gw + x / *step;
    const int dx = x % *step, dy = y % *step;
    if (dx * dx + dy * dy < distance[b]) distance[b] = dx * dx + dy * dy, nearest[b] = i;
  }
  std::vector<std::size_t> chosen;
  std::vector<int> blocks;
  *mask = Mask(gw, gh, false);
  for (std::size_t b = 0; b < nearest.size(); ++b) {
    if (nearest[b] == std::numeric_limits<std::size_t>::max()) continue;
    chosen.push_back(nearest[b]);
    blocks.push_back(static_cast<int>(b));
    mask->inside[b] = 1;
  }
  PhotometricData grid = SubsetObservations(sample, chosen);
  grid.width = gw;
  grid.height = gh;
  grid.pixels = blocks;
  return grid;
}

NormalPlan PlanWith(const NormalPlan& plan, const ModelCandidate& m) {
  NormalPlan p = plan;
  p.Use(m);
  p.options.progress = nullptr;
  return p;
}

// The mean angle of a solved field to its integrated surface, over the pixels solved.
double FieldIntegrability(const PhotometricData& grid, const Mask& held, const NormalPlan& plan,
                          std::size_t* solved) {
  const NormalResult r = SolveNormalsWithPlan(grid, plan);
  Mask mask = held;
  *solved = 0;
  for (std::size_t p = 0; p < mask.inside.size(); ++p) {
    mask.inside[p] = mask.inside[p] && r.residual.pixels[p] >= 0;
    *solved += mask.inside[p];
  }
  return integrate::IntegrabilityDeg(r.normals, mask, plan.options.threads);
}

}  // namespace

HighlightCheck CheckHighlight(const PhotometricData& sample, NormalPlan& plan) {
  HighlightCheck check;
  ModelChoice& choice = plan.model_choice;
  if (!choice.highlight || sample.pixel_count() == 0) return check;
  check.asked = true;
  Mask held;
  const PhotometricData grid = Grid(sample, kHighlightCheckSide, &check.step, &held);
  const ModelCandidate foil = choice.chosen, highlight = *choice.highlight;
  std::size_t solved_foil = 0, solved_highlight = 0;
  check.foil_deg = FieldIntegrability(grid, held, PlanWith(plan, foil), &solved_foil);
  check.highlight_deg =
      FieldIntegrability(grid, held, PlanWith(plan, highlight), &solved_highlight);
  check.pixels = std::min(solved_foil, solved_highlight);
  // NaN (no pixel with a neighbour) compares false: the foil stays.
  check.highlight_kept = check.highlight_deg < check.foil_deg;
  char text[240];
  std::snprintf(text, sizeof text,
                "; the normal-centred foil predicted best, %s n %.3g also beat Lambert: %s kept, "
                "its normals %.2f deg from their integrated surface against %.2f (%zu pixels, "
                "every %d)",
                reflectance::LobeName(highlight.lobe).c_str(), highlight.shininess,
                check.highlight_kept ? "the highlight" : "the foil",
                check.highlight_kept ? check.highlight_deg : check.foil_deg,
                check.highlight_kept ? check.foil_deg : check.highlight_deg, check.pixels,
                check.step);
  choice.note += text;
  if (check.highlight_kept) plan.Use(highlight);
  return check;
}

}  // namespace iphong::solve
