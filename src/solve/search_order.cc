// The search's last step: the best screened candidates refitted and ordered (NormalSearch's
// SortScores, RefitAndOrder, RefitWinner, search.h).
#include "solve/search.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "solve/internal.h"

namespace iphong::solve {

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

}  // namespace iphong::solve
