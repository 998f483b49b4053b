// Which reading of the recorded values the images support: the values as given against the same
// values re-read through a transfer curve (the sRGB curve, for 8- or 16-bit files that state no
// colour space and were read as linear). A Lambertian fit with highlights censored — the
// effective distance's diffuse test (near/effective_distance.h) — predicts each held-out light on
// the model choice's pixels and folds, under both readings. Display-encoded values read as
// linear make every light's shading about (N·L)^(1/2.2), which no reflectance of the model gives,
// and linear values decoded once more about (N·L)^2.2.
//
// The two readings are compared as densities of the same recorded values (Box and Cox, 1964):
// per pixel, the held-out residuals are taken as Gaussian with a spread proportional to the
// pixel's censoring threshold t (a fraction of its brightness), profiled over that proportion,
//   log L = −(n/2)·log(C/n) − n·log t,   C = Σ r²/t² over the n held-out observations,
// and the re-read values' likelihood gains Σ log g'(v) over them, g the curve (the luminance
// weights applied to each channel's derivative): without that Jacobian a curve that compresses
// the values scores better for compressing them. The held-out costs alone told DiLiGenT's cow
// and harvest and UW's photos put through the curve from linear ones by −4 to 0.4 standard
// errors, the wrong way or not at all; with it by 6.5–35.
#pragma once

#include <cstddef>
#include <functional>

#include "solve/model_choice.h"
#include "solve/normals.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

// The re-reading is taken for the right one beyond this many paired standard errors: real
// captures sit far on either side of it (docs/troubleshooting.md gives the margins measured).
constexpr double kReadingStandardErrors = 3;

struct ReadingComparison {
  std::size_t pixels = 0;    // pixels compared (the spread sample, both readings fitted)
  double cost_as_given = 0;  // mean held-out cost, in units of each pixel's t²
  double cost_reread = 0;
  // Per pixel, the re-reading's held-out log-likelihood less the values': its mean and paired
  // standard error. Positive where the re-reading is the more likely.
  double gain = 0;
  double gain_error = 0;
  bool reread_better = false;  // gain > kReadingStandardErrors · gain_error
  double seconds = 0;
};

// The settings a run with `options` compares readings with: its saturation level, shadow
// threshold, model-choice sample and threads.
ModelChoiceSettings ReadingSettings(const NormalOptions& options);

// `reread` maps a recorded value (in [0, 1] for integer codes) to the value it stands for under
// the other reading; it must increase. `settings.fit` gives the saturation level and shadow
// threshold; its model and censoring are the diffuse test's. Throws std::invalid_argument with
// fewer than 6 images (a held-out fit of fewer than 5 lights says little) or no pixel.
ReadingComparison CompareReadings(const PhotometricData& data,
                                  const std::function<double(double)>& reread,
                                  const ModelChoiceSettings& settings);

}  // namespace iphong::solve
