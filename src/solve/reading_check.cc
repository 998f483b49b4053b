#include "solve/reading_check.h"

#include <stdexcept>
#include <tuple>
#include <vector>

#include "core/timing.h"
#include "solve/normals.h"

namespace iphong::solve {

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
  lambert.lobe = reflectance::Lobe::kLambert;
  lambert.ks_prior_weight = 0;
  ModelChoiceSettings diffuse = settings;
  diffuse.fit.model.lobe = reflectance::Lobe::kLambert;
  diffuse.fit.ks_prior.reset();
  diffuse.fit.censor_bright = true;
  diffuse.fit.shading_weights = {};
  diffuse.starts = nullptr;

  ModelCandidate given_model = lambert, reread_model = lambert;
  const std::vector<double> given = PixelHeldOutCosts(as_given, given_model, pixels, fold, diffuse);
  const std::vector<double> other =
      PixelHeldOutCosts(reread_data, reread_model, pixels, fold, diffuse);
  ReadingComparison out;
  out.pixels = pixels.size();
  out.cost_as_given = given_model.heldout_cost;
  out.cost_reread = reread_model.heldout_cost;
  std::tie(out.gain, out.gain_error) = PairedDifference(given.data(), other.data(), given.size());
  out.reread_better = out.gain > kReadingStandardErrors * out.gain_error;
  out.seconds = SecondsSince(start);
  return out;
}

}  // namespace iphong::solve
