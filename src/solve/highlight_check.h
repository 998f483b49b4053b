// The model choice's last word between a mirror lobe and the normal-centred foil (model_choice.h):
// when the foil predicts the held-out lights best while a mirror lobe also beats Lambert,
// prediction cannot say whether the lobe is a highlight, since both explain the same brightness,
// one by a term that follows the normal and one by tilting the normal toward the mirror direction.
// The normals can: a field bent pixel by pixel toward wherever the lights happened to be is not
// the normal field of any surface. Both models solve the same pixels, a grid over the plan sample,
// and the model whose field lies nearer its own least-squares surface (integrate::
// IntegrabilityDeg) is kept; a tie keeps the foil, which predicted better.
#pragma once

#include <cstddef>

#include "solve/normals.h"

namespace iphong::solve {

// The grid's size: at most this many pixels along the longer side of the sample's bounding box
// (every pixel of a smaller one): two solves of at most 128 × 128 pixels cost a fraction of a
// whole run, and a bend toward the lights is a pixel-to-pixel disagreement that a coarser grid
// still sees (docs/accuracy.md has the measurements).
constexpr int kHighlightCheckSide = 128;

struct HighlightCheck {
  bool asked = false;  // the choice set a highlight to weigh against the foil
  bool highlight_kept = false;
  double foil_deg = 0;       // mean angle to the integrated surface, foil's normals
  double highlight_deg = 0;  // the same for the mirror lobe's
  std::size_t pixels = 0;    // the grid's solved pixels (both models)
  int step = 1;              // the grid's spacing in image pixels
};

// Decides and, when the highlight is kept, makes it the plan's model (plan.options and
// plan.model_choice.chosen), appending the figures to the choice's note. Call after the model
// choice, before anything is measured with the chosen model.
HighlightCheck CheckHighlight(const PhotometricData& sample, NormalPlan& plan);

}  // namespace iphong::solve
