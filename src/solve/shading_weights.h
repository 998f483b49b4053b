// The fit's observation weights by the cosine N·L at which each light strikes the surface
// (PixelFitSettings::shading_weights), from the object's own held-out misfit.
//
// Photometric stereo's models are least true toward the terminator, and the error there is
// systematic, one-signed: real diffuse surfaces fall off faster than the cosine at grazing
// incidence (Fresnel transmission, the surface's roughness shadowing itself), and a renderer that
// shades a mesh with interpolated normals darkens the same band (its triangles shadow each other:
// the rendered bunny of ../shared/data is 0.32 of the cosine at N·L 0.1–0.2, 0.79 at 0.3–0.4).
// An unweighted fit pays for such a bias by tilting the normal away from the oblique lights;
// noise, which averages out, does not tilt it. So the misfit is measured on the object: the
// held-out residuals (each fold's lights predicted by a fit to the others, the model choice's
// folds) of the lit, uncensored observations of a sample of pixels, in units of each pixel's
// brightness, in bands of N·L that each hold a tenth of them. A band's weight is the inverse of
// its expected squared error relative to noise alone, s² / (s² + μ²): μ its mean residual (the
// bias), s the least robust spread of any band (the noise, at least kShadingNoiseFloor). Only the
// lower half of the bands is weighted: the mechanisms above act toward the terminator, while a
// misfit near the mirror direction is the lobe's to explain. The fits then use the weights and the
// misfit is measured again, until the weights settle: a fit less bent by the biased band shows its
// bias more plainly. Where the model holds (an exact render, a photograph whose residuals average
// to zero in every band) the weights stay near 1. The bias the settled weights still measure in
// the weighted bands is then taken off their observations (ShadingWeights::offset): measured on
// held-out lights over the whole object, five numbers, it cannot follow one pixel's normal. That
// bias is measured at normals which absorbed part of it, so the offsets are iterated to the fixed
// point where they equal the bias measured at the normals they place (shading_weights.cc).
#pragma once

#include <vector>

#include "solve/photometric_data.h"
#include "solve/pixel_fit.h"

namespace iphong::solve {

// Bands of N·L the misfit is measured in, each holding a tenth of the sample's observations.
constexpr int kShadingBands = 10;
// Rounds of measuring and refitting at most; they stop when no weight moves by kShadingSettle.
constexpr int kShadingRounds = 20;
constexpr double kShadingSettle = 0.02;
// The noise s is taken as at least this fraction of the pixel's brightness, a photograph's noise
// (kNegligibleLobe's 1 %): on an exact render the least spread is rounding, and a bias of a few
// thousandths — a mesh's facets, a pixel's footprint — would otherwise weigh a band down to
// nothing (a noise-free sphere under 12 lights went from 0.07° to 0.19°).
constexpr double kShadingNoiseFloor = 0.01;
// Rounds of the offsets' fixed point at most (the first is the settled weights' bias); they stop
// when no offset moves by kOffsetSettle, a tenth of kShadingNoiseFloor.
constexpr int kOffsetRounds = 12;
constexpr double kOffsetSettle = 0.001;

struct ShadingMisfit {
  ShadingWeights weights;      // empty: too few observations to measure (every weight 1)
  std::vector<double> bias;    // each band's mean held-out residual, in pixel brightness
  std::vector<double> spread;  // each band's robust spread (1.4826 × median |residual|)
  std::size_t observations = 0;
  int rounds = 0;         // of the weights
  int offset_rounds = 0;  // of the offsets' fixed point
};

// The weights' fixed point on `pixels` (positions in data) over the folds `fold` (one per light),
// with `fit`'s model; each pixel's folds fitted from the global search's normal on all its lights,
// or from starts[i] when given. Empty weights with fewer than 20 observations per band.
ShadingMisfit EstimateShadingWeights(const PhotometricData& data, const PixelFitSettings& fit,
                                     const std::vector<std::size_t>& pixels,
                                     const std::vector<int>& fold, int search_candidates,
                                     int threads, const std::vector<Vec3d>* starts = nullptr);

// Whether b equals a within the settling tolerances: as many bands, no weight apart by
// kShadingSettle, no offset by kOffsetSettle (band edges are not compared: they follow the sample).
bool SameShading(const ShadingWeights& a, const ShadingWeights& b);

}  // namespace iphong::solve
