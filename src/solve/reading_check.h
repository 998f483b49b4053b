// Which reading of the recorded values the images support: the values as given against the same
// values re-read through a transfer curve (the sRGB curve, for 8- or 16-bit files that state no
// colour space and were read as linear), by the held-out cost of a Lambertian fit with highlights
// censored — the effective distance's diffuse test (near/effective_distance.h) — on the same
// pixels and folds of the lights. Display-encoded values read as linear make every light's
// shading about (N·L)^(1/2.2), which no reflectance of the model gives, and linear values decoded
// once more about (N·L)^2.2: whichever reading is wrong predicts held-out photos far worse.
#pragma once

#include <cstddef>
#include <functional>

#include "solve/model_choice.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

// The re-reading is taken for the right one beyond this many paired standard errors. Measured:
// real photos read as linear (DiLiGenT's 8-bit crops and 16-bit cat, UW) have the sRGB reading
// 12–31 standard errors worse; sRGB renders read as linear have it 5–95 better (matte 89–95),
// but a glossy one can hide it (a GGX dome −7, MATLAB's peaks with a Phong lobe 0.9). The same
// real photos saved through the curve: DiLiGenT's ball, cat and pot1 25–57 better, cow, harvest
// and UW −4 to 0.4 (a lobe's tails, interreflections, 12 noisy lights): the check names what it
// can see and has not named a linear capture.
constexpr double kReadingStandardErrors = 3;

struct ReadingComparison {
  std::size_t pixels = 0;    // pixels compared (the model choice's spread sample)
  double cost_as_given = 0;  // mean held-out cost, in units of each pixel's t²
  double cost_reread = 0;
  // cost_as_given − cost_reread per pixel, its mean and paired standard error: positive where
  // the re-reading predicts better.
  double gain = 0;
  double gain_error = 0;
  bool reread_better = false;  // gain > kReadingStandardErrors · gain_error
  double seconds = 0;
};

// `reread` maps a recorded value (in [0, 1] for integer codes) to the value it stands for under
// the other reading. `settings.fit` gives the saturation level and shadow threshold; its model
// and censoring are the diffuse test's. Throws std::invalid_argument with fewer than 6 images
// (a held-out fit of fewer than 5 lights says little) or no pixel.
ReadingComparison CompareReadings(const PhotometricData& data,
                                  const std::function<double(double)>& reread,
                                  const ModelChoiceSettings& settings);

}  // namespace iphong::solve
