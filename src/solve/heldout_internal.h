// The held-out costs the model choice (model_choice.cc) compares models by, and the object's
// typical ks; not part of the public interface (model_choice.h has PixelHeldOutCosts).
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "solve/light_tiles.h"
#include "solve/model_choice.h"
#include "solve/search.h"

namespace iphong::solve::internal {

// A pixel of the choice's sample, its luminance observations as the fit reads them.
struct Sample {
  std::size_t pixel = 0;
  std::vector<double> y, usable;  // K each
  double threshold = 0;
};

// The mean held-out cost of one model over the sample, its standard error and the mean angle
// between the two halves' normals (set in m). Each fold's normal is the global search's on its
// training lights (per tile of the sample under near lights: solve/light_tiles.h), refined by
// the local fit (pixel_fit.h) on the same lights: a candidate on the grid is up to half its
// spacing (~2°) from the training optimum, and a sharp lobe predicted from a normal that far off
// loses to a broad one for that reason alone (a noise-free render of Phong n 30 chose n 38.6 from
// grid normals, 29.6 with 16 times as many candidates). With settings.starts each fold's normal
// is refined from the start instead (no search). Returns the per-pixel costs, for paired
// comparisons.
std::vector<double> HeldOutCost(const PhotometricData& data, ModelCandidate& m,
                                const std::vector<Sample>& sample, const std::vector<int>& fold,
                                const ModelChoiceSettings& settings);

// HeldOutCost's per-pixel parts: each sample pixel's cost and fold angle (degrees) where `which`
// is nonzero (every pixel when null), 0 elsewhere. A pixel's figures do not depend on which
// others are evaluated (near lights' tiles are made from the whole sample).
// `tables`, when given, keeps one model's light tiles and candidate tables between calls on
// parts of the same sample (the race scores a model on a quarter, then on the rest): the second
// call reuses what the first made instead of making it again.
struct HeldOutTables {
  std::vector<LightTile> tiles;                               // made on first use
  std::vector<std::shared_ptr<const CandidateTable>> tables;  // per tile, once made
  std::mutex mutex;
};
void HeldOutPixels(const PhotometricData& data, const ModelCandidate& m,
                   const std::vector<Sample>& sample, const std::vector<int>& fold,
                   const ModelChoiceSettings& settings, const std::vector<char>* which,
                   std::vector<double>& cost, std::vector<double>& angle,
                   HeldOutTables* tables = nullptr);
// The per-pixel model test (NormalOptions::per_pixel_model), after the pixel's full search `r`
// under the object's model (the last full search of `search`). Where the lobe adds under
// kNegligibleLobe of `brightness` to every usable observation the two models are the same there:
// Lambert's, untested. Otherwise each model is searched on each fold's training lights near `r`
// (`fold`, K = table.lights()), and Lambert takes the pixel where its held-out cost is lower by
// more than kPixelModelSignificance paired standard errors (PairedDifference). `buffer`,
// `lambert_cost` and `model_cost` (K each) are the caller's, reused from pixel to pixel.
struct PixelModelTest {
  bool tested = false;   // false: the lobe was negligible
  bool lambert = false;  // Lambert takes the pixel
  double mean = 0;       // Lambert's held-out cost less the model's, per usable light
  double error = 0;      // its standard error, the lights taken as independent
  double scale = 1;      // LeaveOneOutErrorScale under leave-one-out, else 1: the test's error
};
PixelModelTest TestPixelModel(NormalSearch& search, const CandidateTable& table,
                              const SearchResult& r, NormalSearch& lambert_search,
                              const CandidateTable& lambert_table, const double* y,
                              const double* usable, double t, double brightness, const int* fold,
                              std::vector<double>& buffer, double* lambert_cost,
                              double* model_cost);

// Sets a search that the per-pixel test will run near its pixels' answers (either model's) for
// the test's folds `table.fold()`: under leave-one-out each fold keeps all lights but one, and
// its search scores the members of the best kLeaveOneOutCoarse coarse directions and refits
// kLeaveOneOutRefits of them; otherwise all 12 and every refit (NormalSearch::NarrowNearLast).
constexpr int kLeaveOneOutCoarse = 3;
constexpr int kLeaveOneOutRefits = 4;
void PreparePixelTestSearch(NormalSearch& search, const CandidateTable& table);

// m's held-out cost, its standard error and fold angle: the means over the pixels given.
void SetHeldOutSummary(ModelCandidate& m, const std::vector<double>& cost,
                       const std::vector<double>& angle);

// Pixels spread over the object (SpreadIndices) with at least 3 usable observations (in each
// fold's training lights, with `fold`).
std::vector<Sample> SamplePixels(const PhotometricData& data, const ModelChoiceSettings& settings,
                                 const std::vector<int>* fold);

// The object's typical ks (RGB) under `model`: the median over the sample of each pixel's ks at
// its searched (or started) normal, with its censoring.
Vec3d SharedSpecular(const PhotometricData& data, const ModelCandidate& model,
                     const ModelChoiceSettings& settings);

}  // namespace iphong::solve::internal
