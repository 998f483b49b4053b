// Held-out costs by cross-validation over the lights (HeldOutSearch, HeldOutFromStart, search.h).
#include "solve/search.h"

#include <algorithm>
#include <cmath>

#include "solve/internal.h"

namespace iphong::solve {

namespace {

// The fold loop of every held-out cost: fold f's lights held out, `fit(training)` fitting the
// others (false: nothing to predict) and `predicted(j)` then the luminance it predicts for light
// j, each held-out usable observation charged its censored cost in units of t².
template <typename Fit, typename Predicted>
HeldOutResult FoldLoop(int k, const double* y, const double* usable, const int* fold, double t,
                       std::vector<double>& buffer, double* per_light, bool censor_bright, Fit fit,
                       Predicted predicted) {
  if (per_light) std::fill(per_light, per_light + k, 0.0);
  const int folds = 1 + *std::max_element(fold, fold + k);
  buffer.resize(k);
  HeldOutResult out;
  for (int f = 0; f < folds; ++f) {
    // Fitted to every light but fold f's, charged for fold f's.
    for (int j = 0; j < k; ++j) buffer[j] = fold[j] == f ? 0.0 : usable[j];
    Vec3d normal;
    if (!fit(buffer.data(), &normal)) continue;
    if (f < 2) out.normal[f] = normal;
    for (int j = 0; j < k; ++j) {
      if (fold[j] != f || usable[j] == 0) continue;
      const double r = y[j] - predicted(j);
      const double cost = internal::CensoredCost(censor_bright ? -std::abs(r) : r, t) / (t * t);
      out.cost += cost;
      if (per_light) per_light[j] = cost;
    }
  }
  return out;
}

}  // namespace

HeldOutResult HeldOutSearch(NormalSearch& search, const CandidateTable& table, const double* y,
                            const double* usable, const int* fold, double t,
                            std::vector<double>& buffer, bool near_last, HeldOutRefiner* refiner,
                            double* per_light) {
  SearchResult r;
  return FoldLoop(
      table.lights(), y, usable, fold, t, buffer, per_light, false,
      [&](const double* training, Vec3d* normal) {
        r = search.Search(y, training, t, nullptr, near_last);
        if (r.candidate < 0) return false;
        *normal = refiner ? refiner->Refine(table.normal(r.candidate), training)
                          : table.normal(r.candidate);
        return true;
      },
      [&](int j) {
        return refiner
                   ? refiner->Predicted(j)
                   : r.kd * table.diffuse(r.candidate)[j] + r.ks * table.specular(r.candidate)[j];
      });
}

HeldOutResult HeldOutFromStart(HeldOutRefiner& refiner, const Vec3d& start, int lights,
                               const double* y, const double* usable, const int* fold, double t,
                               std::vector<double>& buffer, double* per_light, bool censor_bright) {
  return FoldLoop(
      lights, y, usable, fold, t, buffer, per_light, censor_bright,
      [&](const double* training, Vec3d* normal) {
        *normal = refiner.Refine(start, training);
        return true;
      },
      [&](int j) { return refiner.Predicted(j); });
}

}  // namespace iphong::solve
