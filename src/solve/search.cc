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
  unlit_.reserve(table.lights());
  fold_unusable_.assign(table.folds(), 0);
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
      const int c = i < count[q] ? candidates[q][i] : -1;
      const double* at = base_from_ + base_stride_ * std::max(c, 0);
      for (int m = 0; m < 3; ++m) gathered_[q][m * W + i] = c >= 0 ? at[m] : 0.0;
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

SearchResult NormalSearch::Search(const double* y, const double* usable, double t,
                                  const double* fixed_ks, bool near_last) {
  const int k = table_.lights();
  const std::vector<int>& fold = table_.fold();
  const int folds = table_.folds();
  lit_.clear();
  unlit_.clear();
  for (int j = 0; j < k; ++j) {
    y_[j] = static_cast<float>(y[j]);
    usable_[j] = usable[j] != 0 ? 1.0f : 0.0f;
    (usable_[j] != 0 ? lit_ : unlit_).push_back(j);
  }
  const int unusable = static_cast<int>(unlit_.size());
  // The sums Σ d², Σ d s, Σ s² over the usable lights: the table's over every light or over a
  // fold's training lights — whichever holds them all and the fewest others (a fold's base holds
  // them when every light of the fold is unusable; the first such fold wins a tie) — less those
  // few others' terms (saturated observations, mostly); summed directly only when more than a
  // quarter of the base would be left out. Only the folds of unusable lights can hold them, so
  // only those few are counted (fold_unusable_ is all zeros between searches).
  base_ = -1;
  int fewest = unusable;
  if (folds > 0) {
    held_folds_.clear();
    for (const int j : unlit_) {
      if (fold_unusable_[fold[j]]++ == 0) held_folds_.push_back(fold[j]);
    }
    std::sort(held_folds_.begin(), held_folds_.end());
    for (const int f : held_folds_) {
      if (fold_unusable_[f] == table_.fold_size(f) && unusable - table_.fold_size(f) < fewest) {
        base_ = f;
        fewest = unusable - table_.fold_size(f);
      }
      fold_unusable_[f] = 0;
    }
  }
  from_table_ = 4 * fewest <= k;
  base_from_ = table_.base_sums(base_, 0);
  base_stride_ = table_.base_sums(base_, 1) - base_from_;
  excluded_.clear();
  for (const int j : unlit_) {
    if (from_table_ && (base_ < 0 || fold[j] != base_)) excluded_.push_back(j);
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

}  // namespace iphong::solve
