#include "solve/image_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/parallel.h"
#include "core/timing.h"
#include "reflectance/phong.h"
#include "solve/internal.h"
#include "solve/model_choice.h"
#include "solve/pixel_fit.h"

namespace iphong::solve {

namespace {

// The median of `v` (reordered); NaN when empty.
double Median(std::vector<double>& v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t half = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + half, v.end());
  const double upper = v[half];
  if (v.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + half));
}

}  // namespace

std::string ImageCheckOptions::Validate() const {
  if (sample < 1) return "image check: a sample of at least one pixel needed";
  if (!(saturation > 0 && saturation <= 1)) return "image check: saturation must be in (0, 1]";
  if (!(shadow_threshold > 0)) return "image check: the shadow threshold must be positive";
  return "";
}

ImageCheck CheckImages(const PhotometricData& data, const NormalResult& result,
                       const ImageCheckOptions& options) {
  if (const std::string m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  const auto start = Clock::now();
  const int k = data.images;
  ImageCheck check;
  check.misfit.assign(k, std::numeric_limits<double>::quiet_NaN());
  check.score.assign(k, std::numeric_limits<double>::quiet_NaN());
  check.observations.assign(k, 0);
  if (k < 3 || data.pixel_count() == 0 || !result.ambiguity_deg.pixels.empty()) return check;
  if (result.normals.width != data.width || result.normals.height != data.height ||
      result.normals.channels != 3 || result.albedo.pixels.size() != result.normals.pixels.size()) {
    throw std::invalid_argument("image check: the result is not a solve of these images");
  }
  const bool specular = result.specular.pixels.size() == result.normals.pixels.size();
  PixelFitSettings settings;
  settings.model.lobe = result.model;
  settings.shininess = result.shininess;
  settings.known_ks = options.known_ks;
  settings.ambient_term = result.ambient_term;
  settings.code_offset = result.code_offset;
  settings.saturation = options.saturation;
  settings.shadow_threshold = options.shadow_threshold;
  check.heldout = k <= options.heldout_images;
  // A fit of the others that censors what is brighter than it as it censors shadows: a second
  // wrong image (the other line of a swapped pair) cannot pull it either.
  settings.censor_bright = true;
  reflectance::ModelOptions model;
  model.lobe = result.model;
  // Per sample pixel and image, |y − model| / t where the observation is usable, else NaN.
  const std::size_t count = std::min(options.sample, data.pixel_count());
  const std::vector<std::size_t> sample =
      SpreadIndices(data.pixel_count(), static_cast<int>(count));
  std::vector<double> misfit(sample.size() * k, std::numeric_limits<double>::quiet_NaN());
  std::vector<char> solved(sample.size(), 0);
  ParallelFor(0, sample.size(), 64, options.threads, [&](std::size_t b, std::size_t e) {
    PixelFitter fitter(data, settings);
    PixelLights lights(data);
    std::vector<double> training(k);
    for (std::size_t i = b; i < e; ++i) {
      const std::size_t p = sample[i];
      const std::size_t at = static_cast<std::size_t>(data.pixels[p]);
      if (!result.residual.pixels.empty() && result.residual.pixels[at] < 0) continue;
      const auto rgb = [&](const ImageF& image) {
        return Vec3d(image.pixels[3 * at], image.pixels[3 * at + 1], image.pixels[3 * at + 2]);
      };
      const Vec3d normal = rgb(result.normals);
      if (!normal.allFinite() || !(normal.squaredNorm() > 0.5) || !fitter.Prepare(p)) continue;
      solved[i] = 1;
      double* out = &misfit[i * k];
      const double* y = fitter.luminance();
      const double* usable = fitter.usable();
      const double t = fitter.threshold();
      if (check.heldout) {
        // The fit to the other images, from the solved normal, predicts image j.
        for (int j = 0; j < k; ++j) {
          if (usable[j] == 0) continue;
          for (int m = 0; m < k; ++m) training[m] = m == j ? 0.0 : usable[m];
          internal::PixelSolution s;
          s.normal = normal;
          fitter.Fit(s, training.data());
          out[j] = std::abs(y[j] - fitter.Predicted(j)) / t;
        }
        continue;
      }
      const double kd = internal::Luminance(rgb(result.albedo));
      const double ks = specular ? internal::Luminance(rgb(result.specular)) : 0.0;
      lights.At(p);
      for (int j = 0; j < k; ++j) {
        if (usable[j] == 0) continue;
        const reflectance::LightFactors<double> f = reflectance::ShadingFactors<double>(
            normal, lights.view(), lights.direction(j), result.shininess, model);
        out[j] = std::abs(y[j] - kd * f.diffuse - ks * f.specular) / t;
      }
    }
  });
  std::vector<std::vector<double>> misfits(k);
  for (std::size_t i = 0; i < sample.size(); ++i) {
    check.pixels += solved[i];
    for (int j = 0; j < k; ++j) {
      if (!std::isnan(misfit[i * k + j])) misfits[j].push_back(misfit[i * k + j]);
    }
  }
  std::vector<double> judged;
  for (int j = 0; j < k; ++j) {
    check.observations[j] = misfits[j].size();
    if (misfits[j].size() < options.min_pixels) continue;
    check.misfit[j] = Median(misfits[j]);
    judged.push_back(check.misfit[j]);
  }
  check.seconds = SecondsSince(start);
  if (judged.size() < 6) return check;
  check.checked = true;
  check.typical_misfit = Median(judged);
  for (double& v : judged) v = std::abs(v - check.typical_misfit);
  const double spread = Median(judged);
  for (int j = 0; j < k; ++j) {
    if (std::isnan(check.misfit[j])) continue;
    const double above = check.misfit[j] - check.typical_misfit;
    // Every image alike (an exact render): only an image above them all stands out.
    check.score[j] = spread > 0  ? 0.6745 * above / spread
                     : above > 0 ? std::numeric_limits<double>::infinity()
                                 : 0.0;
    if (check.score[j] > kImageDisagreementZ && check.misfit[j] > 1) check.disagreeing.push_back(j);
  }
  return check;
}

}  // namespace iphong::solve
