// Is the per-pixel model test's standard error right? Many captures of one pixel, each with its
// own lights (uniform in a 55° cone about the view) and its own Gaussian noise, go through the full
// search under the object's model and the solver's own test (internal::TestPixelModel: the gate on
// a negligible lobe, both models' held-out searches near the full one over LightFolds(K), and
// PairedDifference). A calibrated standard error is, in root mean square over the captures, the
// spread of their mean differences. Shared by tests/solve/test_model_choice.cc and
// bench/pixel_test_calibration.cc.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "reflectance/phong.h"
#include "solve/heldout_internal.h"
#include "solve/internal.h"
#include "solve/model_choice.h"
#include "solve/search.h"

namespace iphong::solve::test_data {

struct ProbeCase {
  reflectance::Lobe truth = reflectance::Lobe::kLambert;  // the pixel's true model
  double shininess = 1, kd = 1, ks = 0;
  double tilt_deg = 0;  // the normal's angle from the view
  int lights = 12;
  double noise = 0.01;  // Gaussian σ as a fraction of the pixel's brightness
  reflectance::Lobe model = reflectance::Lobe::kBlinnPhong;  // the object's model
  double model_shininess = 20;
};

struct ProbeResult {
  int tested = 0;       // captures the gate let through
  double mean = 0;      // of the mean paired differences (Lambert − model; > 0: model better)
  double spread = 0;    // their standard deviation over the captures
  double stated = 0;    // root mean square of the standard errors PairedDifference stated
  double scaled = 0;    // the same, scaled as the test scales them (LeaveOneOutErrorScale)
  double untested = 0;  // share of the captures whose lobe was negligible
  double lambert = 0;   // share of the tested that the test gave to Lambert
};

inline ProbeResult Probe(const ProbeCase& c, int draws, std::mt19937_64& rng) {
  std::normal_distribution<double> gauss(0, 1);
  std::uniform_real_distribution<double> uniform(0, 1);
  const double cone = std::cos(55 * M_PI / 180), tilt = c.tilt_deg * M_PI / 180;
  const Vec3d normal(std::sin(tilt), 0, std::cos(tilt)), view(0, 0, 1);
  reflectance::ModelOptions truth, model, lambert;
  truth.lobe = c.truth;
  model.lobe = c.model;
  lambert.lobe = reflectance::Lobe::kLambert;
  const std::vector<int> fold = LightFolds(c.lights);
  std::vector<double> buffer, lambert_cost(c.lights), model_cost(c.lights);
  double sum = 0, sq = 0, stated = 0, scaled = 0;
  int untested = 0, lambert_wins = 0, tested = 0;
  for (int d = 0; d < draws; ++d) {
    std::vector<Vec3d> lights(c.lights);
    std::vector<double> y(c.lights), usable(c.lights, 1.0);
    for (int j = 0; j < c.lights; ++j) {
      const double z = cone + (1 - cone) * uniform(rng), phi = 2 * M_PI * uniform(rng);
      const double r = std::sqrt(1 - z * z);
      lights[j] = Vec3d(r * std::cos(phi), r * std::sin(phi), z);
      const auto f =
          reflectance::ShadingFactors<double>(normal, view, lights[j], c.shininess, truth);
      y[j] = c.kd * f.diffuse + c.ks * f.specular;
    }
    std::vector<double> sorted = y;
    const double clean = internal::BrightnessScale(sorted);
    for (double& v : y) v += c.noise * clean * gauss(rng);
    sorted = y;
    const double brightness = internal::BrightnessScale(sorted), t = 0.1 * brightness;
    const CandidateTable table(lights, model, c.model_shininess, 1000, fold);
    const CandidateTable lambert_table(lights, lambert, 1.0, 1000, fold);
    NormalSearch search(table), lambert_search(lambert_table);
    internal::PreparePixelTestSearch(search, table);  // as the solver sets its searches
    internal::PreparePixelTestSearch(lambert_search, lambert_table);
    const SearchResult r = search.Search(y.data(), usable.data(), t, nullptr);
    if (r.candidate < 0) continue;
    // The solver's own test (internal::TestPixelModel), without the object's ks prior.
    const internal::PixelModelTest test = internal::TestPixelModel(
        search, table, r, lambert_search, lambert_table, y.data(), usable.data(), t, brightness,
        fold.data(), buffer, lambert_cost.data(), model_cost.data());
    if (!test.tested) {
      ++untested;
      continue;
    }
    const double mean = test.mean, error = test.error;
    const double scale = test.scale;
    ++tested;
    sum += mean, sq += mean * mean;
    stated += error * error, scaled += scale * scale * error * error;
    if (test.lambert) ++lambert_wins;  // the test as it is
  }
  ProbeResult out;
  out.tested = tested;
  out.untested = static_cast<double>(untested) / draws;
  if (tested == 0) return out;
  out.mean = sum / tested;
  out.spread = std::sqrt(std::max(0.0, sq / tested - out.mean * out.mean));
  out.stated = std::sqrt(stated / tested);
  out.scaled = std::sqrt(scaled / tested);
  out.lambert = static_cast<double>(lambert_wins) / tested;
  return out;
}

}  // namespace iphong::solve::test_data
