#include "solve/search.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstring>

#include "solve/internal.h"

namespace iphong::solve {
namespace {

using VecF = Eigen::Map<const Eigen::VectorXf>;

}  // namespace

std::vector<Vec3d> HemisphereDirections(int count) {
  std::vector<Vec3d> out;
  out.reserve(count);
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = (i + 0.5) / count;  // uniform in z: equal areas on the sphere
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    out.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return out;
}

CandidateTable::CandidateTable(const std::vector<Vec3d>& light_dir_cam,
                               const reflectance::ModelOptions& model, double shininess, int count,
                               const std::vector<int>& fold)
    : lights_(static_cast<int>(light_dir_cam.size())),
      fine_(count),
      fold_(fold),
      normals_(HemisphereDirections(count)) {
  const std::vector<Vec3d> coarse = HemisphereDirections(std::max(4, count / 4));
  normals_.insert(normals_.end(), coarse.begin(), coarse.end());
  members_.resize(coarse.size());
  // The spiral's z is (i + 0.5)/m, and two directions an angle a apart differ in z by at most a,
  // so the nearest coarse direction — within the coarse spacing — is among those whose z lies
  // within twice that spacing (exact, and m/(4·sqrt(2πm)) times fewer comparisons than all).
  const int m = static_cast<int>(coarse.size());
  const double window = 2 * std::sqrt(2 * M_PI / m);
  for (int f = 0; f < count; ++f) {
    const double z = normals_[f].z();
    const int lo = std::clamp(static_cast<int>(std::floor((z - window) * m - 0.5)), 0, m - 1);
    const int hi = std::clamp(static_cast<int>(std::ceil((z + window) * m - 0.5)), 0, m - 1);
    int nearest = lo;
    for (int c = lo + 1; c <= hi; ++c) {
      if (coarse[c].dot(normals_[f]) > coarse[nearest].dot(normals_[f])) nearest = c;
    }
    members_[nearest].push_back(f);
  }
  const std::size_t k = lights_;
  diffuse_.resize(normals_.size() * k);
  specular_.resize(normals_.size() * k);
  sums_.resize(3 * normals_.size());
  for (std::size_t c = 0; c < normals_.size(); ++c) {
    double dd = 0, ds = 0, ss = 0;
    for (std::size_t j = 0; j < k; ++j) {
      const reflectance::LightFactors<double> f = reflectance::ShadingFactors<double>(
          normals_[c], internal::ViewCam(), light_dir_cam[j], shininess, model);
      diffuse_[c * k + j] = static_cast<float>(f.diffuse);
      specular_[c * k + j] = static_cast<float>(f.specular);
      // The sums from the stored (float) factors, as the pixels' dot products will see them.
      const double d = diffuse_[c * k + j], s = specular_[c * k + j];
      dd += d * d;
      ds += d * s;
      ss += s * s;
    }
    sums_[3 * c] = dd;
    sums_[3 * c + 1] = ds;
    sums_[3 * c + 2] = ss;
  }
  if (fold_.size() != k) {
    fold_.clear();
    return;
  }
  const int folds = fold_.empty() ? 0 : 1 + *std::max_element(fold_.begin(), fold_.end());
  // Each fold's own lights' sums, then the training lights' as all lights' less those: one pass
  // over the table whatever the number of folds (leave-one-out has K of them).
  fold_sums_.assign(folds, std::vector<double>(sums_.size(), 0.0));
  for (std::size_t c = 0; c < normals_.size(); ++c) {
    for (std::size_t j = 0; j < k; ++j) {
      double* own = &fold_sums_[fold_[j]][3 * c];
      const double d = diffuse_[c * k + j], s = specular_[c * k + j];
      own[0] += d * d, own[1] += d * s, own[2] += s * s;
    }
  }
  for (int f = 0; f < folds; ++f) {
    for (std::size_t i = 0; i < sums_.size(); ++i) {
      // Sums of non-negative terms (and of d·s ≥ 0): never below zero but for rounding.
      fold_sums_[f][i] = std::max(0.0, sums_[i] - fold_sums_[f][i]);
    }
  }
}

std::pair<double, double> NormalSearch::Solve(double d, double x, double s, double a, double b,
                                              const double* fixed_ks) const {
  if (fixed_ks) return {d > 1e-12 ? std::max(0.0, (a - *fixed_ks * x) / d) : 0.0, *fixed_ks};
  const internal::CoefficientPair<double> c =
      ks_prior_ ? internal::NonNegativePair(d, x, s, a, b, prior_weight_, *ks_prior_)
                : internal::NonNegativePair(d, x, s, a, b);
  return {c.kd, c.ks};
}

NormalSearch::NormalSearch(const CandidateTable& table, int refine, std::optional<double> ks_prior,
                           double prior_weight)
    : table_(table),
      refine_(std::max(1, refine)),
      ks_prior_(ks_prior),
      prior_weight_(prior_weight) {
  y_.resize(table.lights());
  usable_.resize(table.lights());
  weight_.resize(table.lights());
  next_weight_.resize(table.lights());
  scores_.reserve(table.size());
}

double NormalSearch::Cost(int c, double t, double kd, double ks) const {
  const int k = table_.lights();
  const VecF d(table_.diffuse(c), k), s(table_.specular(c), k), y(y_.data(), k),
      u(usable_.data(), k);
  // One fused expression: no temporary array per candidate.
  return ((y.array() - static_cast<float>(kd) * d.array() - static_cast<float>(ks) * s.array())
              .max(static_cast<float>(-t))
              .square() *
          u.array())
      .sum();
}

bool NormalSearch::Refit(int c, double t, const double* fixed_ks, int round, double* kd, double* ks,
                         double* cost) {
  const int k = table_.lights();
  const VecF d(table_.diffuse(c), k), s(table_.specular(c), k), y(y_.data(), k);
  // The censoring's weights into the member buffers (no allocation per candidate). A plain loop:
  // Eigen evaluates a comparison cast to float one value at a time, the compiler vectorizes this.
  const float fkd = static_cast<float>(*kd), fks = static_cast<float>(*ks);
  const float floor = static_cast<float>(-t);
  for (int j = 0; j < k; ++j) {
    const float r = y_[j] - fkd * d[j] - fks * s[j];
    next_weight_[j] = r >= floor ? usable_[j] : 0.0f;
  }
  // The same observations censored as in this candidate's last round: the same fit. (Weights
  // are exactly 0 or 1, so their bytes compare.)
  if (round > 0 && std::memcmp(next_weight_.data(), weight_.data(), k * sizeof(float)) == 0) {
    return false;
  }
  std::swap(weight_, next_weight_);
  const Eigen::Map<const Eigen::ArrayXf> w(weight_.data(), k);
  const auto wd = w * d.array();
  const auto ws = w * s.array();
  const auto [new_kd, new_ks] =
      Solve((wd * d.array()).sum(), (wd * s.array()).sum(), (ws * s.array()).sum(),
            (wd * y.array()).sum(), (ws * y.array()).sum(), fixed_ks);
  *kd = new_kd;
  *ks = new_ks;
  *cost = Cost(c, t, new_kd, new_ks);
  return true;
}

SearchResult NormalSearch::Search(const double* y, const double* usable, double t,
                                  const double* fixed_ks, bool near_last) {
  const int k = table_.lights();
  for (int j = 0; j < k; ++j) {
    y_[j] = static_cast<float>(y[j]);
    usable_[j] = usable[j] != 0 ? 1.0f : 0.0f;
  }
  // The sums Σ d², Σ d s, Σ s² over the usable lights: the table's over every light or over a
  // fold's training lights — whichever holds them all and the fewest others — less those few
  // others' terms (saturated observations, mostly); summed directly only when more than a
  // quarter of the base would be left out.
  const std::vector<int>& fold = table_.fold();
  int base = -1;
  std::size_t fewest = static_cast<std::size_t>(k) + 1;
  for (int b = -1; b < table_.folds(); ++b) {
    std::size_t left_out = 0;
    bool holds = true;
    for (int j = 0; j < k && holds; ++j) {
      const bool in_base = b < 0 || fold[j] != b;
      holds = in_base || usable_[j] == 0;
      left_out += in_base && usable_[j] == 0;
    }
    if (holds && left_out < fewest) base = b, fewest = left_out;
  }
  const bool from_table = 4 * fewest <= static_cast<std::size_t>(k);
  excluded_.clear();
  for (int j = 0; j < k && from_table; ++j) {
    if ((base < 0 || fold[j] != base) && usable_[j] == 0) excluded_.push_back(j);
  }
  const VecF yv(y_.data(), k), u(usable_.data(), k);
  const Eigen::VectorXf yu = yv.cwiseProduct(u);
  const auto score = [&](int c) {
    const VecF d(table_.diffuse(c), k), s(table_.specular(c), k);
    double sd, sx, sss;
    if (from_table) {
      const double* sums = table_.base_sums(base, c);
      sd = sums[0], sx = sums[1], sss = sums[2];
      for (const int j : excluded_) {
        const double dj = d[j], sj = s[j];
        sd -= dj * dj, sx -= dj * sj, sss -= sj * sj;
      }
    } else {
      sd = d.cwiseProduct(u).dot(d), sx = d.cwiseProduct(u).dot(s), sss = s.cwiseProduct(u).dot(s);
    }
    const auto [kd, ks] = Solve(sd, sx, sss, d.dot(yu), s.dot(yu), fixed_ks);
    return Scored{Cost(c, t, kd, ks), c, kd, ks};
  };
  scores_.clear();
  if (!near_last) {
    for (int c = table_.fine_count(); c < table_.size(); ++c) scores_.push_back(score(c));
    const int coarse_top = std::min<int>(12, static_cast<int>(scores_.size()));
    // The best 12, in order: selection then a sort of those few (a heap over all was 5 % of a run).
    std::nth_element(scores_.begin(), scores_.begin() + coarse_top - 1, scores_.end());
    std::sort(scores_.begin(), scores_.begin() + coarse_top);
    last_coarse_.clear();
    for (int i = 0; i < coarse_top; ++i) last_coarse_.push_back(scores_[i].candidate);
  }
  for (int c : last_coarse_) {
    for (int f : table_.members(c)) scores_.push_back(score(f));
  }
  const int top = std::min<int>(refine_, static_cast<int>(scores_.size()));
  if (top > 0) {
    std::nth_element(scores_.begin(), scores_.begin() + top - 1, scores_.end());
    std::sort(scores_.begin(), scores_.begin() + top);
  }
  for (int i = 0; i < top; ++i) {
    Scored& s = scores_[i];
    // From the screening's least-squares coefficients, two rounds of the censoring's weights
    // (the second only when the first changed which observations are censored).
    for (int round = 0; round < 2; ++round) {
      if (!Refit(s.candidate, t, fixed_ks, round, &s.kd, &s.ks, &s.cost)) break;
    }
  }
  // Insertion sort: stable (ties keep their screening order), and no buffer per search as
  // std::stable_sort takes; `top` is at most `refine` (16).
  for (int i = 1; i < top; ++i) {
    for (int j = i; j > 0 && scores_[j].cost < scores_[j - 1].cost; --j)
      std::swap(scores_[j], scores_[j - 1]);
  }
  SearchResult best;
  if (top == 0) return best;
  best = {scores_[0].candidate, scores_[0].cost, scores_[0].kd, scores_[0].ks, {-1, -1}};
  const double apart = std::cos(kOtherBasinDeg * M_PI / 180);
  std::size_t found = 0;
  for (int i = 1; i < top && found < best.others.size(); ++i) {
    const Vec3d& n = table_.normal(scores_[i].candidate);
    bool distinct = n.dot(table_.normal(best.candidate)) < apart;
    for (std::size_t o = 0; o < found; ++o)
      distinct = distinct && n.dot(table_.normal(best.others[o])) < apart;
    if (distinct) best.others[found++] = scores_[i].candidate;
  }
  return best;
}

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
