// The candidates the model choice compares and the statistics it compares them with: the family
// of lobes from the widest that is still a highlight, the light folds, the paired differences of
// held-out costs and their standard errors, the spread sample and the ambient estimate.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "solve/model_choice.h"

namespace iphong::solve {

double LobeHalfWidthDeg(reflectance::Lobe lobe, double shininess) {
  // (R·V)^n = 1/2 at cos ψ = 2^(−1/n), ψ the angle between L and V's mirror direction. N·H
  // turns half as fast as L, so a Blinn-Phong lobe is twice as wide in the light's angle. The
  // foil's (N·L)^n is Phong's about the normal instead of the mirror direction.
  const double psi = std::acos(std::pow(0.5, 1.0 / std::max(shininess, 1e-9))) * 180 / M_PI;
  return lobe == reflectance::Lobe::kBlinnPhong ? 2 * psi : psi;
}

double MinimumShininess(reflectance::Lobe lobe) {
  if (lobe == reflectance::Lobe::kOrenNayar) return 0.05;
  const double half = kMaxLobeHalfWidthDeg * M_PI / 180;
  const double n = std::log(0.5) / std::log(std::cos(half));  // Phong: ψ = the half width
  return lobe == reflectance::Lobe::kBlinnPhong ? std::log(0.5) / std::log(std::cos(half / 2)) : n;
}

std::vector<ModelCandidate> ModelFamily(std::optional<reflectance::Lobe> only) {
  std::vector<ModelCandidate> family;
  using reflectance::Lobe;
  if (!only || *only == Lobe::kLambert) family.push_back({Lobe::kLambert, 1});
  if (!only || *only == Lobe::kOrenNayar) {
    for (int i = 0; i < 5; ++i) family.push_back({Lobe::kOrenNayar, 0.1 * std::pow(2.0, i)});
  }
  for (Lobe lobe : {Lobe::kPhong, Lobe::kBlinnPhong, Lobe::kNormalCentred}) {
    if (only && *only != lobe) continue;
    // Six factors of 2 from the widest lobe that is still a highlight: half widths 30° … ~4°.
    for (int i = 0; i < 6; ++i) family.push_back({lobe, MinimumShininess(lobe) * std::pow(2.0, i)});
  }
  return family;
}

std::pair<double, double> PairedDifference(const double* a, const double* b, std::size_t n,
                                           const double* use) {
  double count = 0, sum = 0, sq = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (use && use[i] == 0) continue;
    const double d = b ? a[i] - b[i] : a[i];
    count += 1, sum += d, sq += d * d;
  }
  if (count == 0) return {0.0, 0.0};
  const double mean = sum / count;
  return {mean, std::sqrt(std::max(0.0, sq / count - mean * mean) / count)};
}

double LeaveOneOutErrorScale(double n) { return n > 1 ? std::sqrt(1 + n / (n - 1)) : 1.0; }

void MakeDiffuseTest(ModelCandidate& model, ModelChoiceSettings& settings) {
  model.lobe = reflectance::Lobe::kLambert;
  model.ks_prior_weight = 0;
  settings.fit.model.lobe = reflectance::Lobe::kLambert;
  settings.fit.ks_prior.reset();
  settings.fit.censor_bright = true;
  settings.fit.shading_weights = {};
}

std::vector<std::size_t> SpreadIndices(std::size_t n, int count) {
  std::vector<std::size_t> out;
  if (n <= static_cast<std::size_t>(std::max(count, 0))) {
    out.resize(n);
    std::iota(out.begin(), out.end(), std::size_t{0});
    return out;
  }
  const double step = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i < count; ++i) {
    const double u = std::fmod(0.5 + i * step, 1.0);
    out.push_back(std::min(n - 1, static_cast<std::size_t>(u * static_cast<double>(n))));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<int> LightFolds(int lights) {
  const int folds = FoldCount(lights);
  std::vector<int> fold(std::max(lights, 0));
  for (int j = 0; j < lights; ++j) fold[j] = j % folds;
  std::mt19937 rng(20261123);
  std::shuffle(fold.begin(), fold.end(), rng);
  return fold;
}

int FoldCount(int lights) {
  if (lights - kMinTrainingLights <= 0) return lights;
  const int f = static_cast<int>(
      std::ceil(static_cast<double>(lights) / (lights - kMinTrainingLights) - 1e-9));
  return std::clamp(f, 2, lights);
}

Vec3d EstimateAmbient(const PhotometricData& data) {
  const std::size_t pixels = data.pixel_count();
  if (pixels == 0) return Vec3d::Zero();
  Vec3d out;
  std::vector<double> darkest(pixels);
  for (int c = 0; c < 3; ++c) {
    for (std::size_t p = 0; p < pixels; ++p) {
      const float* obs = data.pixel(p);
      double m = INFINITY;
      for (int j = 0; j < data.images; ++j) m = std::min(m, static_cast<double>(obs[3 * j + c]));
      darkest[p] = m;
    }
    const std::size_t q = pixels / 4;
    std::nth_element(darkest.begin(), darkest.begin() + q, darkest.end());
    out[c] = std::max(0.0, darkest[q]);
  }
  return out;
}

}  // namespace iphong::solve
