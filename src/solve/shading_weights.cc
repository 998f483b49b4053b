#include "solve/shading_weights.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "core/parallel.h"
#include "solve/light_tiles.h"
#include "solve/search.h"

namespace iphong::solve {
namespace {

// Observations a band needs for its mean to be measured (fewer in the sample: no weights; in a
// band of the offsets' rounds: its offset kept).
constexpr std::size_t kBandObservations = 20;

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
  // The sample's held-out residuals under `fit`, sorted by N·L: the same observations in the same
  // order whatever the threads' interleaving.
  const auto measure = [&] {
    std::vector<Residual> seen;
    std::mutex merge;
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
    std::sort(seen.begin(), seen.end(), [](const Residual& a, const Residual& b) {
      return a.n_dot_l != b.n_dot_l ? a.n_dot_l < b.n_dot_l : a.value < b.value;
    });
    return seen;
  };
  for (int round = 0; round < kShadingRounds; ++round) {
    const std::vector<Residual> seen = measure();
    if (seen.size() < kBandObservations * static_cast<std::size_t>(kShadingBands))
      return ShadingMisfit{};
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
  if (out.weights.empty()) return out;
  // What the settled weights still leave, the bias of the weighted bands, is taken off their
  // observations: the weights keep a biased band from bending the fit, the offset keeps what
  // remains of its pull from bending it one way. The bias measured at the weighted fit's normals
  // is short of the band's own, since those normals absorbed part of it; so the offsets are
  // iterated: each round's offsets are the Phong model's held-out bias at the normals the previous
  // round's offsets placed (not added to them), in the weights' bands, weights held. If the
  // normals absorb a fraction g < 1 of the bias left unexplained, that map is a contraction of
  // ratio g whose fixed point is the band's bias itself.
  std::vector<double> offset(kShadingBands, 0.0);
  for (int band = 0; band < kShadingBands; ++band) {
    offset[band] = std::clamp(TerminatorBias(out.bias, band), -1.0, 1.0);
  }
  out.weights.offset = offset;
  out.offset_rounds = 1;
  double last_move = std::numeric_limits<double>::infinity();
  for (int round = 1; round < kOffsetRounds; ++round) {
    fit.shading_weights = out.weights;
    const std::vector<Residual> seen = measure();
    std::vector<double> sum(kShadingBands, 0.0);
    std::vector<std::size_t> count(kShadingBands, 0);
    for (const Residual& r : seen) {
      const std::size_t band = out.weights.Band(r.n_dot_l);
      sum[band] += r.value;
      ++count[band];
    }
    double moved = 0;
    for (int band = 0; band < kShadingBands; ++band) {
      // A band the normals moved nearly every observation out of keeps its offset.
      if (count[band] < kBandObservations) continue;
      offset[band] =
          std::clamp(TerminatorBias(sum, band) / static_cast<double>(count[band]), -1.0, 1.0);
      moved = std::max(moved, std::abs(offset[band] - out.weights.offset[band]));
    }
    // A step no shorter than the last: the map is not contracting here (or the steps are down to
    // the sample's jitter); the last round's offsets are kept.
    if (moved >= last_move) break;
    last_move = moved;
    out.weights.offset = offset;
    out.offset_rounds = round + 1;
    if (moved < kOffsetSettle) break;
  }
  return out;
}

bool SameShading(const ShadingWeights& a, const ShadingWeights& b) {
  if (a.upper.size() != b.upper.size() || a.offset.size() != b.offset.size()) return false;
  for (std::size_t i = 0; i < a.upper.size(); ++i) {
    if (std::abs(a.weight[i] - b.weight[i]) >= kShadingSettle) return false;
  }
  for (std::size_t i = 0; i < a.offset.size(); ++i) {
    if (std::abs(a.offset[i] - b.offset[i]) >= kOffsetSettle) return false;
  }
  return true;
}

}  // namespace iphong::solve
