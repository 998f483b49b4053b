// Normal recovery in bands of rows, for captures whose observations do not fit in memory: the
// whole-object decisions (normals.h: PlanNormals) on the plan sample drawn in a first pass over
// the bands, then every band fitted with that plan and handed on as soon as it is done. The
// result is bit for bit the one EstimateNormals gives on the whole capture (the same sample, the
// same plan, and each pixel fitted on its own observations alone), whatever the band height.
//
// The numerical core reads no files: `read` supplies a band's observations (PhotometricData of
// width × (y1 − y0), pixel indices within the band) and `write` takes its results.
#pragma once

#include <functional>

#include "solve/normals.h"

namespace iphong::solve {

struct BandSource {
  int width = 0;
  int height = 0;
  std::size_t masked_pixels = 0;  // over the whole image: the plan sample is drawn from them
  // Observations of rows [y0, y1), top to bottom: in two passes when the model is to be chosen
  // (the first draws the plan sample), in one for Woodham or known coefficients. `first_pass`
  // is true on the first pass over the capture, whichever it is.
  std::function<PhotometricData(int y0, int y1, bool first_pass)> read;
};

struct BandProgress {
  // Called with the pass (1: drawing the plan sample, 2: fitting; 3, 4, ...: the effective light
  // distance's near passes, near/effective_distance.h) and the rows done.
  std::function<void(int pass, int rows_done)> rows;
  // Called once with the plan sample's observations when pass 1 has drawn them, before the plan
  // is made: what a check of the whole capture (the CLI's encoding check) can read of it.
  std::function<void(const PhotometricData& sample)> sample;
};

// Calls `write(y0, band)` for each band in order, band the results of rows [y0, y0 + rows) as
// SolveNormalsWithPlan gives them. Returns the whole-object result without images: the model,
// ks (FinishNormals), the summed summary. Throws std::invalid_argument as EstimateNormals.
// `plan`, when given, receives the plan every band was fitted with.
NormalResult EstimateNormalsInBands(const BandSource& source, int band_rows,
                                    const NormalOptions& options,
                                    const std::function<void(int y0, const NormalResult&)>& write,
                                    const BandProgress& progress = {}, NormalPlan* plan = nullptr);

// A result's whole-object fields alone (no images).
NormalResult ResultFields(const NormalResult& result);
// A result's per-pixel images (normals, albedo, specular, residual, model map) for rows
// [y0, y1), and the same pasted back into a whole result at row y0 (its images sized on the first
// paste); the whole-object fields are the source's.
NormalResult ResultRows(const NormalResult& whole, int y0, int y1);
void PasteResultRows(NormalResult& whole, const NormalResult& band, int y0, int width, int height);

}  // namespace iphong::solve
