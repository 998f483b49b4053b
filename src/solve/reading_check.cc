#include "solve/reading_check.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "core/timing.h"
#include "solve/internal.h"
#include "solve/normals.h"
#include "solve/pixel_fit.h"

namespace iphong::solve {
namespace {

// Σ over pixel i's usable observations of log dy'/dy, y the luminance: each channel's derivative
// of the curve, by central differences, weighed as the luminance weighs the channels.
double LogJacobian(const PhotometricData& data, std::size_t i, const double* usable,
                   const std::function<double(double)>& reread) {
  constexpr double kStep = 1e-4;
  const double weight[3] = {internal::Luminance(Vec3d(1, 0, 0)),
                            internal::Luminance(Vec3d(0, 1, 0)),
                            internal::Luminance(Vec3d(0, 0, 1))};
  double sum = 0;
  for (int j = 0; j < data.images; ++j) {
    if (usable[j] == 0) continue;
    const float* v = data.pixel(i) + 3 * j;
    double slope = 0;
    for (int c = 0; c < 3; ++c) {
      const double x = std::max<double>(v[c], kStep);
      slope += weight[c] * (reread(x + kStep) - reread(x - kStep)) / (2 * kStep);
    }
    sum += std::log(std::max(slope, 1e-12));
  }
  return sum;
}

}  // namespace

ModelChoiceSettings ReadingSettings(const NormalOptions& options) {
  ModelChoiceSettings settings;
  settings.fit.saturation = options.saturation;
  settings.fit.shadow_threshold = options.shadow_threshold;
  settings.sample = options.model_sample;
  settings.threads = options.threads;
  return settings;
}

ReadingComparison CompareReadings(const PhotometricData& data,
                                  const std::function<double(double)>& reread,
                                  const ModelChoiceSettings& settings) {
  const auto start = Clock::now();
  if (data.images < 6) {
    throw std::invalid_argument("comparing readings needs 6 images or more");
  }
  if (data.pixel_count() == 0) throw std::invalid_argument("comparing readings needs a pixel");
  const PhotometricData as_given =
      SubsetObservations(data, SpreadIndices(data.pixel_count(), settings.sample));
  PhotometricData reread_data = as_given;
  for (float& v : reread_data.values) v = static_cast<float>(reread(v));
  std::vector<std::size_t> pixels(as_given.pixel_count());
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = i;
  const std::vector<int> fold = LightFolds(data.images);

  ModelCandidate lambert;
  ModelChoiceSettings diffuse = settings;
  MakeDiffuseTest(lambert, diffuse);
  diffuse.starts = nullptr;  // both readings searched from scratch

  ModelCandidate given_model = lambert, reread_model = lambert;
  const std::vector<double> given = PixelHeldOutCosts(as_given, given_model, pixels, fold, diffuse);
  const std::vector<double> other =
      PixelHeldOutCosts(reread_data, reread_model, pixels, fold, diffuse);

  // Each pixel's profiled log-likelihoods, where both readings fit it on the same lights (a value
  // saturated under one reading and not the other, or an exact fit, leaves it out).
  PixelFitSettings fit = diffuse.fit;
  fit.color_residuals = false;
  PixelFitter fit_given(as_given, fit), fit_other(reread_data, fit);
  std::vector<double> gain;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    if (!(given[i] > 0 && other[i] > 0) || !fit_given.Prepare(i) || !fit_other.Prepare(i)) {
      continue;
    }
    const double* usable = fit_given.usable();
    if (!std::equal(usable, usable + data.images, fit_other.usable())) continue;
    const double n = static_cast<double>(std::count(usable, usable + data.images, 1.0));
    const double log_given =
        -0.5 * n * std::log(given[i] / n) - n * std::log(fit_given.threshold());
    const double log_other = -0.5 * n * std::log(other[i] / n) -
                             n * std::log(fit_other.threshold()) +
                             LogJacobian(as_given, i, usable, reread);
    gain.push_back(log_other - log_given);
  }
  ReadingComparison out;
  out.pixels = gain.size();
  out.cost_as_given = given_model.heldout_cost;
  out.cost_reread = reread_model.heldout_cost;
  std::tie(out.gain, out.gain_error) = PairedDifference(gain.data(), nullptr, gain.size());
  out.reread_better = out.gain > kReadingStandardErrors * out.gain_error;
  out.seconds = SecondsSince(start);
  return out;
}

}  // namespace iphong::solve
