#include "solve/search.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "solve/internal.h"
#include "solve/search_lanes.h"

namespace iphong::solve {

static_assert(kSearchLanes == internal::kLanes, "the packed blocks are the lane kernels' width");

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
  // The spiral's z is (i + 0.5)/m, and two directions an angle a apart differ in z by at most a,
  // so the nearest coarse direction — within the coarse spacing — is among those whose z lies
  // within twice that spacing (exact, and m/(4·sqrt(2πm)) times fewer comparisons than all).
  const int m = static_cast<int>(coarse.size());
  const double window = 2 * std::sqrt(2 * M_PI / m);
  std::vector<std::vector<int>> owned(m);
  for (int f = 0; f < count; ++f) {
    const double z = normals_[f].z();
    const int lo = std::clamp(static_cast<int>(std::floor((z - window) * m - 0.5)), 0, m - 1);
    const int hi = std::clamp(static_cast<int>(std::ceil((z + window) * m - 0.5)), 0, m - 1);
    int nearest = lo;
    for (int c = lo + 1; c <= hi; ++c) {
      if (coarse[c].dot(normals_[f]) > coarse[nearest].dot(normals_[f])) nearest = c;
    }
    owned[nearest].push_back(f);
  }
  // The fine directions stored grouped by their coarse one, so each group is scored as one range.
  std::vector<Vec3d> fine;
  fine.reserve(count);
  members_.resize(m);
  for (int c = 0; c < m; ++c) {
    for (const int f : owned[c]) {
      members_[c].push_back(static_cast<int>(fine.size()));
      fine.push_back(normals_[f]);
    }
  }
  normals_ = std::move(fine);
  normals_.insert(normals_.end(), coarse.begin(), coarse.end());
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
  const std::size_t lanes = kSearchLanes;
  const std::size_t blocks = (normals_.size() + lanes - 1) / lanes;
  diffuse_packed_.assign(blocks * k * lanes, 0.0f);
  specular_packed_.assign(blocks * k * lanes, 0.0f);
  sums_packed_.assign(blocks * 3 * lanes, 0.0);
  for (std::size_t c = 0; c < normals_.size(); ++c) {
    for (std::size_t i = 0; i < 3; ++i) {
      sums_packed_[(c / lanes) * 3 * lanes + i * lanes + c % lanes] = sums_[3 * c + i];
    }
    const std::size_t at = (c / lanes) * k * lanes + c % lanes;
    for (std::size_t j = 0; j < k; ++j) {
      diffuse_packed_[at + j * lanes] = diffuse_[c * k + j];
      specular_packed_[at + j * lanes] = specular_[c * k + j];
      has_lobe_ = has_lobe_ || specular_[c * k + j] != 0;
    }
  }
  if (fold_.size() != k) fold_.clear();
  const int folds = fold_.empty() ? 0 : 1 + *std::max_element(fold_.begin(), fold_.end());
  fold_size_.assign(folds, 0);
  for (const int f : fold_) ++fold_size_[f];
  // Each fold's own lights' sums, then the training lights' as all lights' less those: one pass
  // over the table whatever the number of folds (leave-one-out has K of them).
  fold_sums_.assign(3 * folds * normals_.size(), 0.0);
  for (std::size_t c = 0; c < normals_.size() && folds > 0; ++c) {
    double* own = &fold_sums_[3 * folds * c];
    for (std::size_t j = 0; j < k; ++j) {
      double* f = own + 3 * fold_[j];
      const double d = diffuse_[c * k + j], s = specular_[c * k + j];
      f[0] += d * d, f[1] += d * s, f[2] += s * s;
    }
    for (std::size_t i = 0; i < 3 * static_cast<std::size_t>(folds); ++i) {
      // Sums of non-negative terms (and of d·s ≥ 0): never below zero but for rounding.
      own[i] = std::max(0.0, sums_[3 * c + i % 3] - own[i]);
    }
  }
}

void NormalSearch::SolveLanes(const WideLanes& d, const WideLanes& x, const WideLanes& s,
                              const WideLanes& a, const WideLanes& b, const double* fixed_ks,
                              WideLanes* kd, WideLanes* ks) const {
  // The five sums side by side, as the lane kernel reads them.
  Eigen::Array<double, kSearchLanes, 5> sums;
  sums << d, x, s, a, b;
  const internal::PairSettings p = pair_settings(fixed_ks);
  internal::SearchLaneKernels().pair(sums.data(), p.prior_weight, p.prior_ks, p.ridge, fixed_ks,
                                     kd->data(), ks->data());
}

NormalSearch::NormalSearch(const CandidateTable& table, int refine, std::optional<double> ks_prior,
                           double prior_weight)
    : table_(table),
      refine_(std::max(1, refine)),
      ks_prior_(ks_prior),
      prior_weight_(prior_weight),
      near_refits_(refine_) {
  y_.resize(table.lights());
  usable_.resize(table.lights());
  zero_row_.assign(static_cast<std::size_t>(table.lights()) * kSearchLanes, 0.0f);
  lit_.reserve(table.lights());
  keep_ = std::max(refine_, kCoarseTop);
  scores_.reserve(keep_);
  heap_.reserve(keep_);
  costs_.reserve(keep_);
  sorted_.reserve(keep_);
  rank_.reserve(keep_);
  order_.reserve(keep_);
}

void NormalSearch::ScoreRange(int begin, int end, double t, const double* fixed_ks) {
  int lanes[4][kSearchLanes];
  const float* diffuse[4];
  const float* specular[4];
  const double* sums[4];
  const int* candidates[4] = {lanes[0], lanes[1], lanes[2], lanes[3]};
  int count[4];
  // From the last block down: the spiral's directions rise toward the camera with their index,
  // and most surfaces face it, so the best few are met early and the kept set seldom changes.
  // Four blocks a call, the last few two or one (their results kept in the blocks' order, as
  // one at a time would keep them).
  const int low = begin / kSearchLanes;
  int n = 1;
  for (int block = (end - 1) / kSearchLanes; block >= low; block -= n) {
    const int remaining = block - low + 1;
    n = remaining >= 4 ? 4 : remaining >= 2 ? 2 : 1;
    for (int q = 0; q < n; ++q) {
      const int at = block - q;
      const int first = std::max(begin, at * kSearchLanes);
      const int last = std::min(end, (at + 1) * kSearchLanes);
      // Lanes before `first` hold candidates outside the range: scored, not reported.
      const int offset = first - at * kSearchLanes;
      for (int i = 0; i < kSearchLanes; ++i) lanes[q][i] = i < offset ? -1 : at * kSearchLanes + i;
      diffuse[q] = table_.diffuse_block(at);
      specular[q] = table_.specular_block(at);
      sums[q] = table_.sums_block(at);
      count[q] = last - at * kSearchLanes;
    }
    ScoreBlocks(n, diffuse, specular, sums, candidates, count, false, t, fixed_ks);
  }
}

void NormalSearch::PackNear(std::size_t groups) {
  constexpr std::size_t W = kSearchLanes;
  const std::size_t k = table_.lights();
  near_.clear();
  near_scored_ = 0;
  for (std::size_t g = 0; g < std::min(groups, last_coarse_.size()); ++g) {
    const std::vector<int>& members = table_.members(last_coarse_[g]);
    near_.insert(near_.end(), members.begin(), members.end());
    if (g < static_cast<std::size_t>(near_coarse_)) near_scored_ = near_.size();
  }
  const std::size_t blocks = (near_.size() + W - 1) / W;
  near_diffuse_.resize(blocks * k * W);
  near_specular_.resize(blocks * k * W);
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t count = std::min(W, near_.size() - b * W);
    PackBlock(near_.data() + b * W, count, near_diffuse_.data() + b * k * W,
              near_specular_.data() + b * k * W);
  }
}

void NormalSearch::PackBlock(const int* candidates, std::size_t count, float* diffuse,
                             float* specular) {
  constexpr std::size_t W = kSearchLanes;
  const std::size_t k = table_.lights();
  // Every lane written, eight lights at a time by a transpose in registers, lanes past `count`
  // from a row of zeros (an empty candidate): no fill of the buffer first, no strided stores.
  const float *d[W], *s[W];
  for (std::size_t i = 0; i < W; ++i) {
    d[i] = i < count ? table_.diffuse(candidates[i]) : zero_row_.data();
    s[i] = i < count ? table_.specular(candidates[i]) : zero_row_.data();
  }
  internal::SearchLaneKernels().pack(d, static_cast<int>(k), diffuse);
  internal::SearchLaneKernels().pack(s, static_cast<int>(k), specular);
}

void NormalSearch::ScoreBlocks(int blocks, const float* const* diffuse,
                               const float* const* specular, const double* const* sums,
                               const int* const* candidates, const int* count, bool near, double t,
                               const double* fixed_ks) {
  constexpr int W = kSearchLanes;
  // Σ d², Σ d s, Σ s² (double, the 2 × 2 system's): a regular block's over every light come
  // packed with it; otherwise gathered from the table's base, or summed over the usable lights
  // (the kernel does that when given none).
  const double* base[4] = {nullptr, nullptr, nullptr, nullptr};
  for (int q = 0; q < blocks && from_table_; ++q) {
    if (sums[q] && base_ < 0) {
      base[q] = sums[q];
      continue;
    }
    for (int i = 0; i < W; ++i) {
      const bool in = i < count[q] && candidates[q][i] >= 0;
      const double* c = in ? table_.base_sums(base_, candidates[q][i]) : nullptr;
      for (int m = 0; m < 3; ++m) gathered_[q][m * W + i] = in ? c[m] : 0.0;
    }
    base[q] = gathered_[q];
  }
  // Then the least-squares pair and the censored cost Σ_j max(y_j − kd d_j − ks s_j, −t)² over
  // the usable lights, and by how much the censoring clips (positive where it censors anything).
  const internal::LaneKernels& kernels = internal::SearchLaneKernels();
  if (blocks > 1) {
    (blocks == 4 ? kernels.score4 : kernels.score2)(
        diffuse, specular, table_.has_lobe(), lit_.data(), static_cast<int>(lit_.size()), y_.data(),
        base, excluded_.data(), static_cast<int>(excluded_.size()), pair_settings(fixed_ks),
        static_cast<float>(-t), block_score_);
  } else {
    kernels.score(diffuse[0], specular[0], table_.has_lobe(), lit_.data(),
                  static_cast<int>(lit_.size()), y_.data(), base[0], excluded_.data(),
                  static_cast<int>(excluded_.size()), pair_settings(fixed_ks),
                  static_cast<float>(-t), block_score_);
  }
  for (int q = 0; q < blocks; ++q) {
    Keep(block_score_[q], diffuse[q], candidates[q], count[q], near);
  }
}

void NormalSearch::Keep(const internal::BlockScore& score, const float* diffuse,
                        const int* candidates, int count, bool near) {
  constexpr int W = kSearchLanes;
  const auto record = [&](Scored* into, int i) {
    // Field by field: an entry built aside and copied whole is read back before its parts have
    // been stored.
    into->cost = score.cost[i];
    into->candidate = candidates[i];
    into->kd = score.kd[i];
    into->ks = score.ks[i];
    into->censors = score.clipped[i] > 0;
    into->near = near;
    into->at =
        static_cast<int>(diffuse - (near ? near_diffuse_.data() : table_.diffuse_block(0))) + i;
  };
  // A search that scores no more than it keeps keeps them all, in the order scored: the heap
  // would have taken each as it came.
  if (keep_all_) {
    for (int i = 0; i < count; ++i) {
      if (candidates[i] >= 0) record(&scores_.emplace_back(), i);
    }
    return;
  }
  // Only the best `keep_` scored so far are kept (no candidate past them can reach the refits or
  // the coarse step's 12), in a heap with the worst on top.
  if (static_cast<int>(scores_.size()) >= keep_) {
    const float worst = heap_.front().cost;
    bool any = false;
    for (int i = 0; i < W; ++i) any = any || score.cost[i] < worst;
    if (!any) return;
  }
  for (int i = 0; i < count; ++i) {
    if (candidates[i] < 0) continue;
    const float cost = score.cost[i];
    Scored* into = nullptr;
    if (static_cast<int>(scores_.size()) < keep_) {
      heap_.push_back(MakeSlot(cost, static_cast<int>(scores_.size())));
      into = &scores_.emplace_back();
      std::push_heap(heap_.begin(), heap_.end());
    } else if (cost < heap_.front().cost) {
      std::pop_heap(heap_.begin(), heap_.end());
      into = &scores_[heap_.back().slot];
      heap_.back() = MakeSlot(cost, heap_.back().slot);
      std::push_heap(heap_.begin(), heap_.end());
    }
    if (into) record(into, i);
  }
}

void NormalSearch::RefitBlock(const int* which, int count, double t, const double* fixed_ks) {
  constexpr int W = kSearchLanes;
  using Lanes = Eigen::Array<float, W, 1>;
  using Wide = WideLanes;
  const std::size_t k = table_.lights();
  // The candidates' factors packed as a block (lanes past `count` zero: nothing fits there).
  refit_diffuse_.resize(k * W);
  refit_specular_.resize(k * W);
  // Gathered from the blocks the candidates were just scored in, which are in cache, rather than
  // from the table's rows (a padding lane from zeros).
  Wide kd0 = Wide::Zero(), ks0 = Wide::Zero();
  const float *d_from[W], *s_from[W];
  for (int i = 0; i < W; ++i) {
    if (i >= count) {
      d_from[i] = s_from[i] = zero_row_.data();
      continue;
    }
    const Scored& s = scores_[which[i]];
    d_from[i] = (s.near ? near_diffuse_.data() : table_.diffuse_block(0)) + s.at;
    s_from[i] = (s.near ? near_specular_.data() : table_.specular_block(0)) + s.at;
    kd0[i] = s.kd, ks0[i] = s.ks;
  }
  for (std::size_t j = 0; j < k; ++j) {
    for (int i = 0; i < W; ++i) refit_diffuse_[j * W + i] = d_from[i][j * W];
    for (int i = 0; i < W; ++i) refit_specular_[j * W + i] = s_from[i][j * W];
  }
  const float* diffuse = refit_diffuse_.data();
  const float* specular = refit_specular_.data();
  const float floor = static_cast<float>(-t);
  const int lit = static_cast<int>(lit_.size());
  // Σ w d², Σ w d s, Σ w s², Σ w d y, Σ w s y with w the censoring's weights at (kd, ks), each
  // light's weights kept in refit_weights_ (K × W) to tell whether the next round censors the same
  // (search_lanes.h).
  using Sums = Eigen::Array<float, W, 5>;
  const auto solve = [&](const Sums& sums, Wide* kd, Wide* ks) {
    SolveLanes(sums.col(0).cast<double>(), sums.col(1).cast<double>(), sums.col(2).cast<double>(),
               sums.col(3).cast<double>(), sums.col(4).cast<double>(), fixed_ks, kd, ks);
  };
  // Round 0 writes every usable light's weights before round 1 compares with them: no fill.
  refit_weights_.resize(k * W);
  // Round 0: the screening fit's weights, and the fit they give.
  Sums first, second;
  Lanes cost1, changed;
  const Lanes fkd0 = kd0.cast<float>(), fks0 = ks0.cast<float>();
  internal::SearchLaneKernels().weighted_sums(
      diffuse, specular, lit_.data(), lit, y_.data(), fkd0.data(), fks0.data(), floor,
      refit_weights_.data(), first.data(), nullptr, nullptr);
  Wide kd1, ks1;
  solve(first, &kd1, &ks1);
  // Its cost, and round 1's weights and sums from its residuals in the same pass.
  const Lanes fkd1 = kd1.cast<float>(), fks1 = ks1.cast<float>();
  internal::SearchLaneKernels().weighted_sums(
      diffuse, specular, lit_.data(), lit, y_.data(), fkd1.data(), fks1.data(), floor,
      refit_weights_.data(), second.data(), cost1.data(), changed.data());
  // Round 1 where it censors differently from round 0: the fit with its weights, and its cost.
  Wide kd2 = kd1, ks2 = ks1;
  Lanes cost2 = cost1;
  if ((changed > 0.0f).any()) {
    solve(second, &kd2, &ks2);
    const Lanes fkd2 = kd2.cast<float>(), fks2 = ks2.cast<float>();
    Lanes clipped;
    internal::SearchLaneKernels().cost(diffuse, specular, true, lit_.data(), lit, y_.data(),
                                       fkd2.data(), fks2.data(), floor, cost2.data(),
                                       clipped.data());
  }
  for (int i = 0; i < count; ++i) {
    Scored& s = scores_[which[i]];
    const bool again = changed[i] > 0;
    s.kd = again ? kd2[i] : kd1[i];
    s.ks = again ? ks2[i] : ks1[i];
    s.cost = again ? cost2[i] : cost1[i];
  }
}

void NormalSearch::SortScores(int n, bool final_order) {
  // The stable order by cost: each entry's place is the count of entries cheaper than it and of
  // equal ones before it, counted without branches; then the entries are moved once. That is the
  // order std::sort gives as well on at most 16 entries (libstdc++ sorts so few by insertion,
  // which is stable) and the final insertion sort gives, so the order before either — each of
  // which is still taken beyond 16 entries or where a cost is NaN, which orders nothing.
  costs_.resize(n);
  bool ordered = n <= 16;
  for (int i = 0; i < n; ++i) {
    costs_[i] = static_cast<float>(scores_[i].cost);
    ordered = ordered && !std::isnan(costs_[i]);
  }
  if (!ordered) {
    if (!final_order) {
      std::sort(scores_.begin(), scores_.begin() + n);
      return;
    }
    for (int i = 1; i < n; ++i) {
      for (int j = i; j > 0 && scores_[j].cost < scores_[j - 1].cost; --j)
        std::swap(scores_[j], scores_[j - 1]);
    }
    return;
  }
  sorted_.resize(n);
  const float* c = costs_.data();
  for (int i = 0; i < n; ++i) {
    int place = 0;
    for (int j = 0; j < n; ++j) place += (c[j] < c[i]) | ((c[j] == c[i]) & (j < i));
    sorted_[place] = scores_[i];
  }
  std::copy(sorted_.begin(), sorted_.end(), scores_.begin());
}

SearchResult NormalSearch::Search(const double* y, const double* usable, double t,
                                  const double* fixed_ks, bool near_last) {
  const int k = table_.lights();
  const std::vector<int>& fold = table_.fold();
  const int folds = table_.folds();
  lit_.clear();
  fold_unusable_.assign(folds, 0);
  int unusable = 0;
  for (int j = 0; j < k; ++j) {
    y_[j] = static_cast<float>(y[j]);
    usable_[j] = usable[j] != 0 ? 1.0f : 0.0f;
    if (usable_[j] != 0) {
      lit_.push_back(j);
    } else {
      ++unusable;
      if (folds > 0) ++fold_unusable_[fold[j]];
    }
  }
  // The sums Σ d², Σ d s, Σ s² over the usable lights: the table's over every light or over a
  // fold's training lights — whichever holds them all and the fewest others (a fold's base holds
  // them when every light of the fold is unusable) — less those few others' terms (saturated
  // observations, mostly); summed directly only when more than a quarter of the base would be
  // left out.
  base_ = -1;
  int fewest = unusable;
  for (int f = 0; f < folds; ++f) {
    if (fold_unusable_[f] == table_.fold_size(f) && unusable - table_.fold_size(f) < fewest) {
      base_ = f;
      fewest = unusable - table_.fold_size(f);
    }
  }
  from_table_ = 4 * fewest <= k;
  excluded_.clear();
  for (int j = 0; j < k && from_table_; ++j) {
    if ((base_ < 0 || fold[j] != base_) && usable_[j] == 0) excluded_.push_back(j);
  }
  scores_.clear();
  heap_.clear();
  keep_all_ = false;
  if (!near_last) {
    ScoreRange(table_.fine_count(), table_.size(), t, fixed_ks);
    const int coarse_top = std::min<int>(kCoarseTop, static_cast<int>(scores_.size()));
    // The best 12 in order (of the best `keep_` kept), then the heap again.
    SortScores(static_cast<int>(scores_.size()), false);
    last_coarse_.clear();
    for (int i = 0; i < coarse_top; ++i) last_coarse_.push_back(scores_[i].candidate);
    for (std::size_t i = 0; i < scores_.size(); ++i) {
      heap_[i] = {static_cast<float>(scores_[i].cost), static_cast<int>(i)};
    }
    std::make_heap(heap_.begin(), heap_.end());
    near_.clear();
  }
  // A full search packs every one of its best coarse directions' members; a near_last search
  // that finds none packed (its own table's, NearTheLastOf) packs only those it scores.
  if (near_.empty()) PackNear(near_last ? near_coarse_ : last_coarse_.size());
  const std::size_t scored = near_last ? near_scored_ : near_.size();
  keep_all_ = near_last && scored <= static_cast<std::size_t>(keep_);
  const std::size_t block = static_cast<std::size_t>(k) * kSearchLanes;
  const float* diffuse[2];
  const float* specular[2];
  const double* const sums[2] = {nullptr, nullptr};
  const int* candidates[2];
  int count[2];
  for (std::size_t i = 0; i < scored; i += 2 * kSearchLanes) {
    const int n = scored - i > kSearchLanes ? 2 : 1;
    for (int q = 0; q < n; ++q) {
      const std::size_t at = i + q * kSearchLanes;
      diffuse[q] = near_diffuse_.data() + (at / kSearchLanes) * block;
      specular[q] = near_specular_.data() + (at / kSearchLanes) * block;
      candidates[q] = near_.data() + at;
      count[q] = static_cast<int>(std::min<std::size_t>(kSearchLanes, scored - at));
    }
    ScoreBlocks(n, diffuse, specular, sums, candidates, count, true, t, fixed_ks);
  }
  const int top =
      std::min<int>(near_last ? near_refits_ : refine_, static_cast<int>(scores_.size()));
  SearchResult best;
  // A held-out fold's search (near_last) is read for its winner alone.
  if (near_last) {
    const int winner = RefitWinner(top, t, fixed_ks);
    if (winner < 0) return best;
    const Scored& first = scores_[winner];
    return {first.candidate, first.cost, first.kd, first.ks, {-1, -1}};
  }
  RefitAndOrder(top, t, fixed_ks);
  if (top == 0) return best;
  const Scored& first = scores_[order_[0]];
  best = {first.candidate, first.cost, first.kd, first.ks, {-1, -1}};
  const double apart = std::cos(kOtherBasinDeg * M_PI / 180);
  std::size_t found = 0;
  for (int i = 1; i < top && found < best.others.size(); ++i) {
    const Vec3d& n = table_.normal(scores_[order_[i]].candidate);
    bool distinct = n.dot(table_.normal(best.candidate)) < apart;
    for (std::size_t o = 0; o < found; ++o)
      distinct = distinct && n.dot(table_.normal(best.others[o])) < apart;
    if (distinct) best.others[found++] = scores_[order_[i]].candidate;
  }
  return best;
}

int NormalSearch::RefitWinner(int top, double t, const double* fixed_ks) {
  const int n = static_cast<int>(scores_.size());
  if (top <= 0) return -1;
  // RefitAndOrder's order_[0] without ordering the rest: the best `top` by (screening cost,
  // position) picked one at a time, the censoring ones refitted, and the least refitted cost
  // wins, ties to the better screening rank. Beyond 16 entries or with a NaN screening cost,
  // RefitAndOrder itself.
  constexpr int kMost = 16;
  bool counted = n <= kMost;
  for (int i = 0; i < n && counted; ++i) counted = !std::isnan(static_cast<float>(scores_[i].cost));
  if (!counted) {
    RefitAndOrder(top, t, fixed_ks);
    return order_[0];
  }
  // Each entry's (cost, position) as one unsigned key, ordered as the pair is (the float's bits
  // made monotone; +0 for −0, which compares equal to it), so the picks need no branches.
  std::uint64_t key[kMost];
  for (int i = 0; i < n; ++i) {
    std::uint32_t bits;
    const float c = static_cast<float>(scores_[i].cost) + 0.0f;
    std::memcpy(&bits, &c, sizeof bits);
    bits ^= (bits >> 31) != 0 ? 0xffffffffu : 0x80000000u;
    key[i] = (static_cast<std::uint64_t>(bits) << 32) | static_cast<std::uint32_t>(i);
  }
  constexpr std::uint64_t kTaken = ~std::uint64_t{0};
  bool taken[kMost] = {};
  int chosen[kMost];  // chosen[r]: the entry of screening rank r
  for (int r = 0; r < top; ++r) {
    std::uint64_t least = kTaken;
    for (int i = 0; i < n; ++i) least = std::min(least, key[i]);
    chosen[r] = static_cast<int>(least & 0xffffffffu);
    key[chosen[r]] = kTaken;
    taken[chosen[r]] = true;
  }
  refit_.resize(n);
  int refits = 0;
  for (int i = 0; i < n; ++i) {
    refit_[refits] = i;
    refits += taken[i] & scores_[i].censors;
  }
  for (int i = 0; i < refits; i += kSearchLanes) {
    RefitBlock(refit_.data() + i, std::min(kSearchLanes, refits - i), t, fixed_ks);
  }
  bool nan = false;
  for (int r = 0; r < top; ++r)
    nan = nan || std::isnan(static_cast<float>(scores_[chosen[r]].cost));
  if (nan) {
    // As RefitAndOrder orders a NaN: by insertion in screening order, on the costs themselves.
    for (int i = 1; i < top; ++i) {
      for (int j = i; j > 0 && scores_[chosen[j]].cost < scores_[chosen[j - 1]].cost; --j)
        std::swap(chosen[j], chosen[j - 1]);
    }
    return chosen[0];
  }
  int winner = chosen[0];
  float least = static_cast<float>(scores_[winner].cost);
  for (int r = 1; r < top; ++r) {
    const float c = static_cast<float>(scores_[chosen[r]].cost);
    const bool better = c < least;
    winner = better ? chosen[r] : winner;
    least = better ? c : least;
  }
  return winner;
}

void NormalSearch::RefitAndOrder(int top, double t, const double* fixed_ks) {
  const int n = static_cast<int>(scores_.size());
  // The screening's stable order, its best `top` refitted, and those ordered by their refitted
  // cost, ties in screening order. A refit's result does not depend on which others share its
  // block (each lane is its own), so the entries need not be moved in between: one place count
  // on (screening cost, position) and one on (refitted cost, screening place). Beyond 16
  // entries or with a NaN cost the two sorts are made as such (SortScores).
  bool counted = n <= 16;
  for (int i = 0; i < n && counted; ++i) counted = !std::isnan(static_cast<float>(scores_[i].cost));
  rank_.resize(n);
  order_.resize(n);
  costs_.resize(n);
  if (counted) {
    for (int i = 0; i < n; ++i) costs_[i] = static_cast<float>(scores_[i].cost);
    const float* c = costs_.data();
    for (int i = 0; i < n; ++i) {
      int place = 0;
      for (int j = 0; j < n; ++j) place += (c[j] < c[i]) | ((c[j] == c[i]) & (j < i));
      rank_[i] = place;
    }
  } else {
    SortScores(n, false);
    for (int i = 0; i < n; ++i) rank_[i] = i;
  }
  refit_.clear();
  for (int i = 0; i < n; ++i) {
    // From the screening's least-squares coefficients, two rounds of the censoring's weights
    // (the second only when the first changed which observations are censored). Where the
    // screening's fit censors nothing, the first round's weights are the usable lights: its fit
    // is the screening's own, and nothing would change.
    if (rank_[i] < top && scores_[i].censors) refit_.push_back(i);
  }
  for (std::size_t i = 0; i < refit_.size(); i += kSearchLanes) {
    RefitBlock(refit_.data() + i,
               static_cast<int>(std::min<std::size_t>(kSearchLanes, refit_.size() - i)), t,
               fixed_ks);
  }
  for (int i = 0; i < n && counted; ++i) {
    costs_[i] = static_cast<float>(scores_[i].cost);
    counted = !std::isnan(costs_[i]);
  }
  if (counted) {
    const float* c = costs_.data();
    for (int i = 0; i < n; ++i) {
      if (rank_[i] >= top) continue;
      int place = 0;
      for (int j = 0; j < n; ++j) {
        place += (rank_[j] < top) & ((c[j] < c[i]) | ((c[j] == c[i]) & (rank_[j] < rank_[i])));
      }
      order_[place] = i;
    }
    return;
  }
  // The entries moved into screening order, then the refits' order by insertion (stable).
  sorted_.resize(n);
  for (int i = 0; i < n; ++i) sorted_[rank_[i]] = scores_[i];
  std::copy(sorted_.begin(), sorted_.end(), scores_.begin());
  SortScores(top, true);
  for (int i = 0; i < n; ++i) order_[i] = i;
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
