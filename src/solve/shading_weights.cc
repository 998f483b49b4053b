#include "solve/shading_weights.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "core/parallel.h"
#include "solve/light_tiles.h"
#include "solve/search.h"

namespace iphong::solve {
namespace {

// The bias a band is weighed and offset by: its own in the lower half of the bands, toward the
// terminator; none above, where a misfit near the mirror direction is the lobe's to explain.
double TerminatorBias(const std::vector<double>& bias, int band) {
  return band < kShadingBands / 2 ? bias[band] : 0.0;
}

struct Residual {
  double n_dot_l = 0;
  double value = 0;  // held-out residual over the pixel's brightness
};

// Each fold's lights predicted by the fit to the others, from `start`; the lit, uncensored ones
// appended to `out`.
void HeldOutResiduals(PixelFitter& fitter, const Vec3d& start, const std::vector<int>& fold,
                      int folds, std::vector<double>& training, std::vector<Residual>& out) {
  const int k = static_cast<int>(fold.size());
  const double t = fitter.threshold(), brightness = fitter.brightness();
  for (int f = 0; f < folds; ++f) {
    for (int j = 0; j < k; ++j) training[j] = fold[j] == f ? 0.0 : 1.0;
    internal::PixelSolution s;
    s.normal = start;
    fitter.Fit(s, training.data());
    for (int j = 0; j < k; ++j) {
      if (fold[j] != f || fitter.usable()[j] == 0) continue;
      const double c = fitter.Diffuse(j);
      const double r = fitter.luminance()[j] - fitter.Predicted(j);
      if (c > 0 && r >= -t) out.push_back({c, r / brightness});  // a shadow is no misfit
    }
  }
}

}  // namespace

ShadingMisfit EstimateShadingWeights(const PhotometricData& data, const PixelFitSettings& settings,
                                     const std::vector<std::size_t>& pixels,
                                     const std::vector<int>& fold, int search_candidates,
                                     int threads, const std::vector<Vec3d>* starts) {
  ShadingMisfit out;
  if (fold.size() != static_cast<std::size_t>(data.images) || pixels.empty()) return out;
  const int folds = 1 + *std::max_element(fold.begin(), fold.end());
  PixelFitSettings fit = settings;
  fit.shading_weights = {};
  // Each pixel's start: its own, or the search's answer on all its lights (once).
  std::vector<Vec3d> start(pixels.size(), Vec3d::Zero());
  if (starts) {
    start = *starts;
  } else {
    std::vector<std::size_t> index(data.pixel_count(), 0);
    for (std::size_t i = 0; i < pixels.size(); ++i) index[pixels[i]] = i;
    const std::vector<LightTile> tiles =
        MakeLightTiles(data, TileToleranceDeg(fit.model.lobe, fit.shininess), &pixels);
    ForEachTileChunk(
        tiles, 16, threads,
        [&](std::size_t t) {
          return CandidateTable(tiles[t].light_directions, fit.model, fit.shininess,
                                search_candidates);
        },
        [&](std::size_t t, const CandidateTable& table, std::size_t b, std::size_t e) {
          NormalSearch search(table);
          PixelFitter fitter(data, fit);
          for (std::size_t n = b; n < e; ++n) {
            if (!fitter.Prepare(tiles[t].pixels[n])) continue;
            const SearchResult r =
                search.Search(fitter.luminance(), fitter.usable(), fitter.threshold(), nullptr);
            if (r.candidate >= 0) start[index[tiles[t].pixels[n]]] = table.normal(r.candidate);
          }
        });
  }
  std::vector<Residual> seen;
  std::mutex merge;
  for (int round = 0; round < kShadingRounds; ++round) {
    seen.clear();
    ParallelFor(0, pixels.size(), 16, threads, [&](std::size_t b, std::size_t e) {
      PixelFitter fitter(data, fit);
      std::vector<double> training(data.images);
      std::vector<Residual> local;
      for (std::size_t i = b; i < e; ++i) {
        if (start[i].isZero() || !fitter.Prepare(pixels[i])) continue;
        HeldOutResiduals(fitter, start[i], fold, folds, training, local);
      }
      const std::lock_guard lock(merge);
      seen.insert(seen.end(), local.begin(), local.end());
    });
    if (seen.size() < 20 * static_cast<std::size_t>(kShadingBands)) return ShadingMisfit{};
    // The same observations in the same order whatever the threads' interleaving.
    std::sort(seen.begin(), seen.end(), [](const Residual& a, const Residual& b) {
      return a.n_dot_l != b.n_dot_l ? a.n_dot_l < b.n_dot_l : a.value < b.value;
    });
    ShadingMisfit m;
    m.observations = seen.size();
    m.rounds = round + 1;
    std::vector<double> magnitude;
    for (int band = 0; band < kShadingBands; ++band) {
      const std::size_t from = seen.size() * band / kShadingBands;
      const std::size_t to = seen.size() * (band + 1) / kShadingBands;
      double sum = 0;
      magnitude.clear();
      for (std::size_t i = from; i < to; ++i) {
        sum += seen[i].value;
        magnitude.push_back(std::abs(seen[i].value));
      }
      const auto mid = magnitude.begin() + static_cast<std::ptrdiff_t>(magnitude.size() / 2);
      std::nth_element(magnitude.begin(), mid, magnitude.end());
      m.spread.push_back(1.4826 * *mid);
      m.bias.push_back(sum / static_cast<double>(to - from));
      m.weights.upper.push_back(band + 1 < kShadingBands ? seen[to].n_dot_l : 1.0);
    }
    const double noise =
        std::max(*std::min_element(m.spread.begin(), m.spread.end()), kShadingNoiseFloor);
    for (int band = 0; band < kShadingBands; ++band) {
      const double mu = TerminatorBias(m.bias, band);
      m.weights.weight.push_back(noise * noise / (noise * noise + mu * mu));
    }
    double moved = 0;
    for (int band = 0; band < kShadingBands; ++band) {
      moved = std::max(moved, std::abs(m.weights.weight[band] -
                                       (out.weights.empty() ? 1.0 : out.weights.weight[band])));
    }
    out = m;
    fit.shading_weights = out.weights;
    if (moved < kShadingSettle) break;
  }
  // What the settled weights still leave, the bias of the weighted bands, is taken off their
  // observations: the weights keep a biased band from bending the fit, the offset keeps what
  // remains of its pull from bending it one way.
  if (!out.weights.empty()) {
    for (int band = 0; band < kShadingBands; ++band) {
      out.weights.offset.push_back(std::clamp(TerminatorBias(out.bias, band), -1.0, 1.0));
    }
  }
  return out;
}

}  // namespace iphong::solve
