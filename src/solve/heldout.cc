#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <tuple>

#include "core/parallel.h"
#include "solve/heldout_internal.h"
#include "solve/light_tiles.h"
#include "solve/search.h"

namespace iphong::solve {
namespace {

// Censoring rounds of each fold's local fit: the start's censoring and one revision of it.
constexpr int kHeldOutFitRounds = 2;

// The model choice's held-out fits: each fold's search winner refined by the local fit on the
// fold's training lights (luminance), which then predicts the fold.
class LocalFitRefiner : public HeldOutRefiner {
 public:
  explicit LocalFitRefiner(PixelFitter& fitter) : fitter_(fitter) {}
  Vec3d Refine(const Vec3d& start, const double* training) override {
    internal::PixelSolution solution;
    solution.normal = start;
    fitter_.Fit(solution, training);
    return solution.normal;
  }
  double Predicted(int j) const override { return fitter_.Predicted(j); }

 private:
  PixelFitter& fitter_;
};

}  // namespace

namespace internal {

void HeldOutPixels(const PhotometricData& data, const ModelCandidate& m,
                   const std::vector<Sample>& sample, const std::vector<int>& fold,
                   const ModelChoiceSettings& settings, const std::vector<char>* which,
                   std::vector<double>& cost, std::vector<double>& angle, HeldOutTables* tables) {
  reflectance::ModelOptions model;
  model.lobe = m.lobe;
  PixelFitSettings fit = settings.fit;
  fit.model = model;
  fit.shininess = m.shininess;
  fit.known_ks.reset();
  if (m.ks_prior_weight > 0) fit.ks_prior = m.ks_prior, fit.ks_prior_weight = m.ks_prior_weight;
  fit.color_residuals = false;  // the search's luminance
  fit.rounds = kHeldOutFitRounds;
  cost.assign(sample.size(), 0.0);
  angle.assign(sample.size(), 0.0);
  const auto wanted = [&](std::size_t i) { return !which || (*which)[i] != 0; };
  const auto record = [&](std::size_t i, const HeldOutResult& r) {
    cost[i] = r.cost;
    if (!r.normal[0].isZero() && !r.normal[1].isZero()) {
      angle[i] = std::acos(std::clamp(r.normal[0].dot(r.normal[1]), -1.0, 1.0)) * 180 / M_PI;
    }
  };
  if (settings.starts) {
    ParallelFor(0, sample.size(), 16, settings.threads, [&](std::size_t b, std::size_t e) {
      PixelFitter fitter(data, fit);
      LocalFitRefiner refiner(fitter);
      std::vector<double> buffer;
      for (std::size_t i = b; i < e; ++i) {
        const Sample& s = sample[i];
        if (!wanted(i) || !fitter.Prepare(s.pixel)) continue;  // drawn where it succeeds
        record(i, HeldOutFromStart(refiner, (*settings.starts)[s.pixel], data.images,
                                   fitter.luminance(), fitter.usable(), fold.data(),
                                   fitter.threshold(), buffer, nullptr, fit.censor_bright));
      }
    });
  } else {
    // Under near lights each tile of the sample has its own table; the local fit then refines
    // the start with the pixel's own lights, so a tile may be as wide as the lobe's half width.
    std::vector<std::size_t> pixels(sample.size());
    std::vector<std::size_t> index(data.pixel_count(), 0);
    for (std::size_t i = 0; i < sample.size(); ++i) {
      pixels[i] = sample[i].pixel;
      index[sample[i].pixel] = i;
    }
    HeldOutTables own;
    HeldOutTables& kept = tables ? *tables : own;
    if (kept.tiles.empty()) {
      kept.tiles =
          MakeLightTiles(data, std::min(8.0, 2 * TileToleranceDeg(m.lobe, m.shininess)), &pixels);
      kept.tables.assign(kept.tiles.size(), nullptr);
    }
    const std::vector<LightTile>& tiles = kept.tiles;
    ForEachTileChunk(
        tiles, 16, settings.threads,
        [&](std::size_t t) -> std::shared_ptr<const CandidateTable> {
          if (std::none_of(tiles[t].pixels.begin(), tiles[t].pixels.end(),
                           [&](std::size_t p) { return wanted(index[p]); })) {
            return nullptr;  // none of its pixels is scored in this call
          }
          {
            std::lock_guard<std::mutex> lock(kept.mutex);
            if (kept.tables[t]) return kept.tables[t];
          }
          auto table = std::make_shared<const CandidateTable>(
              tiles[t].light_directions, model, m.shininess, settings.search_candidates, fold);
          // Kept for a later call only when there is one to come (the caller holds `tables`).
          if (tables) {
            std::lock_guard<std::mutex> lock(kept.mutex);
            kept.tables[t] = table;
          }
          return table;
        },
        [&](std::size_t t, const std::shared_ptr<const CandidateTable>& held, std::size_t b,
            std::size_t e) {
          if (!held) return;
          const CandidateTable& table = *held;
          NormalSearch search(
              table, 16,
              m.ks_prior_weight > 0 ? std::optional(internal::Luminance(m.ks_prior)) : std::nullopt,
              m.ks_prior_weight);
          PixelFitter fitter(data, fit);
          LocalFitRefiner refiner(fitter);
          std::vector<double> buffer;
          for (std::size_t n = b; n < e; ++n) {
            const std::size_t i = index[tiles[t].pixels[n]];
            const Sample& s = sample[i];
            if (!wanted(i) || !fitter.Prepare(s.pixel)) continue;  // drawn where it succeeds
            record(i, HeldOutSearch(search, table, fitter.luminance(), fitter.usable(), fold.data(),
                                    fitter.threshold(), buffer, false, &refiner));
          }
        });
  }
}

PixelModelTest TestPixelModel(NormalSearch& search, const CandidateTable& table,
                              const SearchResult& r, NormalSearch& lambert_search,
                              const CandidateTable& lambert_table, const double* y,
                              const double* usable, double t, double brightness, const int* fold,
                              std::vector<double>& buffer, double* lambert_cost,
                              double* model_cost) {
  const int k = table.lights();
  double lobe_peak = 0;
  const float* lobe = table.specular(r.candidate);
  for (int j = 0; j < k; ++j) {
    if (usable[j] != 0) lobe_peak = std::max(lobe_peak, r.ks * lobe[j]);
  }
  PixelModelTest out;
  // A model without a lobe departs from Lambert in its diffuse term (Oren–Nayar's): no peak to
  // measure, so every pixel is tested.
  if (table.has_lobe() && lobe_peak <= kNegligibleLobe * brightness) {
    out.lambert = true;
    return out;
  }
  out.tested = true;
  lambert_search.NearTheLastOf(search);
  HeldOutSearch(lambert_search, lambert_table, y, usable, fold, t, buffer, true, nullptr,
                lambert_cost);
  // The specular search above was the last full one of `search`.
  HeldOutSearch(search, table, y, usable, fold, t, buffer, true, nullptr, model_cost);
  std::tie(out.mean, out.error) = PairedDifference(lambert_cost, model_cost, k, usable);
  if (1 + *std::max_element(fold, fold + k) == k) {
    out.scale = LeaveOneOutErrorScale(std::accumulate(usable, usable + k, 0.0));
  }
  out.lambert = out.mean <= -kPixelModelSignificance * out.scale * out.error;
  return out;
}

void PreparePixelTestSearch(NormalSearch& search, const CandidateTable& table) {
  // A fold of all lights but one moves a pixel's answer by what one light says: its winner is
  // mostly among the all-lights search's best few (docs/benchmarks.md has the counts), where a
  // half of the lights leaves it free to go farther.
  if (table.folds() > 0 && table.folds() == table.lights()) {
    search.NarrowNearLast(kLeaveOneOutCoarse, kLeaveOneOutRefits);
  }
}

void SetHeldOutSummary(ModelCandidate& m, const std::vector<double>& cost,
                       const std::vector<double>& angle) {
  const double n = static_cast<double>(std::max<std::size_t>(1, cost.size()));
  double sum = 0, sq = 0;
  for (double c : cost) sum += c, sq += c * c;
  m.heldout_cost = sum / n;
  m.heldout_error = std::sqrt(std::max(0.0, sq / n - m.heldout_cost * m.heldout_cost) / n);
  m.fold_angle_deg = std::accumulate(angle.begin(), angle.end(), 0.0) / n;
}

std::vector<double> HeldOutCost(const PhotometricData& data, ModelCandidate& m,
                                const std::vector<Sample>& sample, const std::vector<int>& fold,
                                const ModelChoiceSettings& settings) {
  std::vector<double> cost, angle;
  HeldOutPixels(data, m, sample, fold, settings, nullptr, cost, angle);
  SetHeldOutSummary(m, cost, angle);
  m.heldout_pixels = cost.size();
  return cost;
}

std::vector<Sample> SamplePixels(const PhotometricData& data, const ModelChoiceSettings& settings,
                                 const std::vector<int>* fold) {
  const int k = data.images;
  std::vector<Sample> sample;
  const std::size_t pixels = data.pixel_count();
  PixelFitter fitter(data, settings.fit);
  for (const std::size_t p : SpreadIndices(pixels, settings.sample)) {
    if (!fitter.Prepare(p)) continue;
    Sample s;
    s.pixel = p;
    s.y.assign(fitter.luminance(), fitter.luminance() + k);
    s.usable.assign(fitter.usable(), fitter.usable() + k);
    s.threshold = fitter.threshold();
    // Every fit (all lights outside one fold) needs 3 usable observations.
    const int folds = fold ? 1 + *std::max_element(fold->begin(), fold->end()) : 2;
    bool enough = true;
    for (int f = 0; f < folds; ++f) {
      int training = 0;
      for (int j = 0; j < k; ++j) training += s.usable[j] != 0 && (fold ? (*fold)[j] : j % 2) != f;
      enough = enough && training >= 3;
    }
    if (enough) sample.push_back(std::move(s));
  }
  return sample;
}

Vec3d SharedSpecular(const PhotometricData& data, const ModelCandidate& model,
                     const ModelChoiceSettings& settings) {
  const std::vector<Sample> sample = SamplePixels(data, settings, nullptr);
  if (sample.empty() || model.lobe == reflectance::Lobe::kLambert) return Vec3d::Zero();
  reflectance::ModelOptions options;
  options.lobe = model.lobe;
  const int k = data.images;
  std::vector<std::array<double, 3>> ks(sample.size(), {0, 0, 0});
  std::vector<int> ok(sample.size(), 0);
  std::vector<std::size_t> pixels(sample.size());
  std::vector<std::size_t> index(data.pixel_count(), 0);
  for (std::size_t i = 0; i < sample.size(); ++i) {
    pixels[i] = sample[i].pixel;
    index[sample[i].pixel] = i;
  }
  // Pixel i's RGB ks at `normal` with the censoring of its luminance fit (kd, ks): the model's
  // factors from the table (distant lights) or from the pixel's own lights (near ones).
  const auto measure = [&](std::size_t i, const Vec3d& normal, const float* table_d,
                           const float* table_s, double kd, double ks_lum, PixelLights& lights,
                           std::vector<reflectance::LightFactors<double>>& f,
                           std::vector<double>& w) {
    const Sample& s = sample[i];
    lights.At(s.pixel);
    for (int j = 0; j < k; ++j) {
      f[j] = table_d ? reflectance::LightFactors<double>{table_d[j], table_s[j]}
                     : reflectance::ShadingFactors<double>(
                           normal, lights.view(), lights.direction(j), model.shininess, options);
    }
    if (!table_d) {
      const auto lum = internal::EliminatedCoefficients<double>(
          f, 1, nullptr, [&](std::size_t j, int) { return s.y[j]; },
          [&](std::size_t j) { return s.usable[j]; });
      kd = lum[0].kd, ks_lum = lum[0].ks;
    }
    for (int j = 0; j < k; ++j) {
      const double r = s.y[j] - kd * f[j].diffuse - ks_lum * f[j].specular;
      w[j] = s.usable[j] * internal::CensoredWeight(r, s.threshold);
    }
    const float* obs = data.pixel(s.pixel);
    const auto c = internal::EliminatedCoefficients<double>(
        f, 3, nullptr,
        [&](std::size_t j, int ch) {
          return lights.lit(j)
                     ? (obs[3 * j + ch] - settings.fit.ambient_term[ch]) / lights.irradiance(j)[ch]
                     : 0.0;
        },
        [&](std::size_t j) { return w[j]; });
    ks[i] = {c[0].ks, c[1].ks, c[2].ks};
    ok[i] = 1;
  };
  if (settings.starts) {
    ParallelFor(0, sample.size(), 16, settings.threads, [&](std::size_t b, std::size_t e) {
      PixelLights lights(data);
      std::vector<reflectance::LightFactors<double>> f(k);
      std::vector<double> w(k);
      for (std::size_t i = b; i < e; ++i) {
        measure(i, (*settings.starts)[sample[i].pixel], nullptr, nullptr, 0, 0, lights, f, w);
      }
    });
  } else {
    const std::vector<LightTile> tiles = MakeLightTiles(
        data, std::min(8.0, 2 * TileToleranceDeg(model.lobe, model.shininess)), &pixels);
    ForEachTileChunk(
        tiles, 16, settings.threads,
        [&](std::size_t t) {
          return CandidateTable(tiles[t].light_directions, options, model.shininess,
                                settings.search_candidates);
        },
        [&](std::size_t t, const CandidateTable& table, std::size_t b, std::size_t e) {
          NormalSearch search(table);
          PixelLights lights(data);
          std::vector<reflectance::LightFactors<double>> f(k);
          std::vector<double> w(k);
          for (std::size_t n = b; n < e; ++n) {
            const std::size_t i = index[tiles[t].pixels[n]];
            const Sample& s = sample[i];
            const SearchResult fit =
                search.Search(s.y.data(), s.usable.data(), s.threshold, nullptr);
            if (fit.candidate < 0) continue;
            // Near lights: the table only placed the normal; the factors are the pixel's own.
            const bool from_table = !data.near();
            measure(
                i, table.normal(fit.candidate), from_table ? table.diffuse(fit.candidate) : nullptr,
                from_table ? table.specular(fit.candidate) : nullptr, fit.kd, fit.ks, lights, f, w);
          }
        });
  }
  Vec3d out;
  for (int c = 0; c < 3; ++c) {
    std::vector<double> v;
    for (std::size_t i = 0; i < ks.size(); ++i)
      if (ok[i]) v.push_back(ks[i][c]);
    if (v.empty()) return Vec3d::Zero();
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    out[c] = v[v.size() / 2];
  }
  return out;
}

}  // namespace internal

using internal::HeldOutCost;
using internal::Sample;

std::vector<double> PixelHeldOutCosts(const PhotometricData& data, ModelCandidate& m,
                                      const std::vector<std::size_t>& pixels,
                                      const std::vector<int>& fold,
                                      const ModelChoiceSettings& settings) {
  std::vector<Sample> sample(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    if (pixels[i] >= data.pixel_count()) throw std::invalid_argument("pixel beyond the data");
    sample[i].pixel = pixels[i];
  }
  if (fold.size() != static_cast<std::size_t>(data.images)) {
    throw std::invalid_argument("one fold per light needed");
  }
  ModelChoiceSettings s = settings;
  s.fit.ambient_term = m.ambient_term;
  s.fit.code_offset = m.code_offset;
  return HeldOutCost(data, m, sample, fold, s);
}

}  // namespace iphong::solve
