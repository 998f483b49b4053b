// The global search of normal recovery. Every pixel's normal is first chosen among a fixed set
// of candidate directions covering the visible hemisphere, by the censored cost of all its
// observations under the model; the local fit (pixel_fit.h) starts from the winner. No start —
// Woodham's, pulled by highlights and shadows — can then leave a pixel in a wrong basin.
//
// For a candidate N the model's factors d_j = max(N·L_j, 0) and s_j = lobe_j(N)
// (reflectance/phong.h) are the same for every pixel: they are tabulated once, C × K, and again
// packed in blocks of kSearchLanes candidates, light-major within a block (K × kSearchLanes), so
// that a pixel scores a block's candidates together, a light at a time, in vector lanes (the
// products Σ_j y_j d_j and Σ_j y_j s_j are a matrix–vector product, the censored cost a fused
// pass of the same shape, and both skip the lights the pixel cannot use). A pixel's
// luminance observations y_j = lum((I_j − Ia⊙ka)/E_j) are fitted at each candidate as
//   y_j ≈ kd·d_j + ks·s_j,   kd, ks ≥ 0 (ks given when the coefficients are known),
// the two coefficients by least squares (internal::NonNegativePair), and the candidate is scored
// by the censored cost Σ_j max(y_j − kd d_j − ks s_j, −t)² (internal::CensoredCost). Coarse to
// fine: a quarter as many coarse directions are scored first; the fine directions nearest to the
// best 12 of them (stored contiguously) are scored next. The best `refine` of all scored are then
// refitted with the censoring's weights (two rounds), as the local fit would, and the lowest
// censored cost wins; a candidate whose least-squares fit censors nothing is already that fit.
// Camera frame, V = (0, 0, 1).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <utility>
#include <vector>

#include "core/types.h"
#include "reflectance/phong.h"
#include "solve/internal.h"
#include "solve/search_lanes.h"

namespace iphong::solve {

// Directions on the visible hemisphere (z > 0), `count` of them on a Fibonacci spiral: equal
// areas, spacing about sqrt(2π/count) radians.
std::vector<Vec3d> HemisphereDirections(int count);

// Candidates scored together (CandidateTable's packed blocks): an AVX register of floats, or two
// SSE ones (solve/search_lanes.h).
constexpr int kSearchLanes = 8;

// Candidates 0 … fine_count() − 1 are the fine directions, the rest the coarse ones.
class CandidateTable {
 public:
  // With `fold` (each light's cross-validation fold, or empty) the sums over each fold's
  // training lights are kept too, so a search on them costs what one on every light does.
  CandidateTable(const std::vector<Vec3d>& light_dir_cam, const reflectance::ModelOptions& model,
                 double shininess, int count, const std::vector<int>& fold = {});
  int size() const { return static_cast<int>(normals_.size()); }
  int fine_count() const { return fine_; }
  // The fine candidates whose nearest coarse direction is coarse candidate c: a contiguous range
  // of indices (the fine directions are stored grouped by their coarse one).
  const std::vector<int>& members(int c) const { return members_[c - fine_]; }
  int lights() const { return lights_; }
  const Vec3d& normal(int c) const { return normals_[c]; }
  const float* diffuse(int c) const {
    return diffuse_.data() + static_cast<std::size_t>(c) * lights_;
  }
  const float* specular(int c) const {
    return specular_.data() + static_cast<std::size_t>(c) * lights_;
  }
  // Block b's factors (candidates kSearchLanes·b …, zero past size()): light j's at
  // [j·kSearchLanes, (j + 1)·kSearchLanes).
  const float* diffuse_block(int b) const {
    return diffuse_packed_.data() + static_cast<std::size_t>(b) * lights_ * kSearchLanes;
  }
  const float* specular_block(int b) const {
    return specular_packed_.data() + static_cast<std::size_t>(b) * lights_ * kSearchLanes;
  }
  // Whether any candidate's lobe is nonzero under any light (false for Lambert).
  bool has_lobe() const { return has_lobe_; }
  // The folds given (empty: none), and {Σ d², Σ d s, Σ s²} of candidate c over every light
  // (base −1: the sums of a pixel with no saturated image) or over those outside fold `base`.
  const std::vector<int>& fold() const { return fold_; }
  int folds() const { return static_cast<int>(fold_size_.size()); }
  const double* base_sums(int base, int c) const {
    return base < 0 ? &sums_[3 * static_cast<std::size_t>(c)]
                    : &fold_sums_[3 * (static_cast<std::size_t>(c) * folds() + base)];
  }
  // Block b's sums over every light (base −1), packed as its factors are: Σ d² of its
  // kSearchLanes candidates, then Σ d s, then Σ s² (zero past size()).
  const double* sums_block(int b) const {
    return sums_packed_.data() + 3 * static_cast<std::size_t>(b) * kSearchLanes;
  }
  // The number of lights in fold f.
  int fold_size(int f) const { return fold_size_[f]; }

 private:
  int lights_ = 0;
  int fine_ = 0;
  std::vector<int> fold_;
  std::vector<int> fold_size_;
  std::vector<Vec3d> normals_;
  std::vector<std::vector<int>> members_;
  std::vector<float> diffuse_, specular_, diffuse_packed_, specular_packed_;
  bool has_lobe_ = false;
  std::vector<double> sums_, sums_packed_;
  // Candidate-major, every fold of a candidate side by side: a pixel's searches on its folds read
  // the same few candidates' sums, which then stay in cache.
  std::vector<double> fold_sums_;
};

struct SearchResult {
  int candidate = -1;  // −1: no candidate explains anything (all observations unusable)
  double cost = 0;     // censored cost at the winner
  double kd = 0, ks = 0;
  // The next best refined candidates in other basins (more than kOtherBasinDeg from the winner
  // and from each other), −1 when none: starts for more local fits. On a grid, a highlight
  // placed a few degrees off costs more than one left out as if shadowed, so the true basin's
  // candidate can come second.
  std::array<int, 2> others = {-1, -1};
};

// Candidates this far apart lie in different basins of a pixel's cost: twice the spacing of the
// default 1000 directions, and narrower than the broadest lobe offered (30°).
constexpr double kOtherBasinDeg = 10;

// One thread's search: buffers are reused from pixel to pixel.
class NormalSearch {
 public:
  // With `ks_prior` (luminance), a free ks is pulled toward it with `prior_weight`
  // (internal::NonNegativePair).
  explicit NormalSearch(const CandidateTable& table, int refine = 16,
                        std::optional<double> ks_prior = std::nullopt, double prior_weight = 0);
  // y: K luminances; usable: K weights 0 (saturated) or 1; t: the censoring threshold;
  // fixed_ks: the luminance ks when known, else nullptr. Only the lights where `usable` is 1
  // count (a held-out fold sets the other half to 0). `near_last`: only the fine directions near
  // the last full search's best coarse ones (the same pixel's held-out halves, whose normals lie
  // near the one all lights found), at a fifth of the cost; fewer with NarrowNearLast.
  SearchResult Search(const double* y, const double* usable, double t, const double* fixed_ks,
                      bool near_last = false);
  // The coarse directions the next `near_last` search looks near: those of `other`'s last full
  // search (a table over the same directions).
  void NearTheLastOf(const NormalSearch& other) {
    last_coarse_ = other.last_coarse_;
    near_.clear();
  }
  // `near_last` searches score only the members of the last full search's best `coarse` coarse
  // directions and refit only their best `refits` (by default all 12 and `refine`): for held-out
  // folds that differ from all the lights by one light, whose winners lie nearer the all-lights
  // answer than those of halves do (solve/heldout.cc).
  void NarrowNearLast(int coarse, int refits) {
    near_coarse_ = std::clamp(coarse, 1, kCoarseTop);
    near_refits_ = std::clamp(refits, 1, refine_);
    near_.clear();
  }

 private:
  // (kd, ks) from the weighted sums D = Σ w d², X = Σ w d s, S = Σ w s², A = Σ w d y, B = Σ w s y
  // of kSearchLanes candidates, one per lane: internal::NonNegativePair (with the ks prior), or
  // kd alone for a fixed ks.
  using WideLanes = Eigen::Array<double, kSearchLanes, 1>;
  void SolveLanes(const WideLanes& d, const WideLanes& x, const WideLanes& s, const WideLanes& a,
                  const WideLanes& b, const double* fixed_ks, WideLanes* kd, WideLanes* ks) const;
  // Scores candidates [begin, end) — the least-squares coefficients on the usable lights and the
  // censored cost there — and appends them to scores_, a packed block at a time.
  void ScoreRange(int begin, int end, double t, const double* fixed_ks);
  // Scores `blocks` (1, 2 or 4) packed blocks (K × kSearchLanes factors each, and with sums[q]
  // their sums over every light packed as CandidateTable::sums_block gives them, else nullptr),
  // lane i of block q holding candidate candidates[q][i] for i < count[q]; `near`: blocks of
  // near_diffuse_, else the table's. The blocks' results are kept (Keep) in their order.
  void ScoreBlocks(int blocks, const float* const* diffuse, const float* const* specular,
                   const double* const* sums, const int* const* candidates, const int* count,
                   bool near, double t, const double* fixed_ks);
  // Keeps a scored block's candidates among the best keep_ (scores_ and heap_).
  void Keep(const internal::BlockScore& score, const float* diffuse, const int* candidates,
            int count, bool near);
  // The 2 × 2 solve's settings: the ks prior (none: NonNegativePair's defaults) and the ridge.
  internal::PairSettings pair_settings(const double* fixed_ks) const {
    return {ks_prior_ ? prior_weight_ : 0.0, ks_prior_ ? *ks_prior_ : 0.0, internal::kKsRidge,
            fixed_ks};
  }
  // Refits the candidates scores_[which[0 … count − 1]] (at most kSearchLanes) together: from
  // the screening's coefficients, the fit with the censoring's weights, and again where that
  // fit censors other observations than the screening's did (two rounds).
  void RefitBlock(const int* which, int count, double t, const double* fixed_ks);
  // Packs the fine candidates near the first `groups` of last_coarse_ (their members) into
  // near_*, grouped by coarse direction in last_coarse_'s order, and sets near_scored_ to how
  // many of them belong to the first near_coarse_: the same few are scored by every search near
  // the last full one (a pixel's held-out folds, both models).
  void PackNear(std::size_t groups);
  // Packs `count` (≤ kSearchLanes) candidates' factors as one block, light-major (k × lanes).
  void PackBlock(const int* candidates, std::size_t count, float* diffuse, float* specular);
  const CandidateTable& table_;
  int refine_;
  std::optional<double> ks_prior_;
  double prior_weight_ = 0;
  std::vector<float> y_, usable_;
  struct Scored {
    double cost;
    int candidate;
    int at;  // its first factor in the packed block it was scored in (lights kSearchLanes apart)
    double kd, ks;  // the least-squares coefficients the cost was taken at
    bool censors;   // whether any usable observation lies more than t below that fit
    bool near;      // scored in near_diffuse_/near_specular_, else in the table's blocks
    bool operator<(const Scored& o) const { return cost < o.cost; }
  };
  // The best candidates scored so far, at most keep_ (refine_, and the coarse step's 12), and a
  // heap of their costs with the worst on top (small entries: what a replacement moves).
  static constexpr int kCoarseTop = 12;
  struct Slot {
    float cost;
    int slot;  // in scores_
    bool operator<(const Slot& o) const { return cost < o.cost; }
  };
  // One 8-byte store: the heap reads a slot back whole, and a read of two 4-byte stores as one
  // waits for them to drain.
  static Slot MakeSlot(float cost, int slot) {
    static_assert(sizeof(Slot) == 8 && offsetof(Slot, slot) == 4, "cost, then slot");
    std::uint32_t bits;
    std::memcpy(&bits, &cost, sizeof bits);
    const std::uint64_t low = bits, high = static_cast<std::uint32_t>(slot);
    // The field at the lower address in the 64-bit word's low half on a little-endian machine.
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    const std::uint64_t packed = (low << 32) | high;
#else
    const std::uint64_t packed = low | (high << 32);
#endif
    Slot out;
    std::memcpy(&out, &packed, sizeof out);
    return out;
  }
  // Orders scores_[0 … n) by cost, ties in their present order (`final_order`: the refits'
  // ordering, else the screening's).
  void SortScores(int n, bool final_order);
  // Refits the best `top` of the scored (in screening order) and leaves order_[0 … top) the
  // indices of scores_ by refitted cost, ties in screening order.
  void RefitAndOrder(int top, double t, const double* fixed_ks);
  // The same refits, and the index in scores_ of what would be order_[0] (−1 when top is 0):
  // all a near_last search reads.
  int RefitWinner(int top, double t, const double* fixed_ks);
  std::vector<float> costs_;
  std::vector<Scored> sorted_;
  std::vector<int> rank_, order_;
  double gathered_[4][3 * kSearchLanes];  // up to four blocks' sums gathered from the table
  internal::BlockScore block_score_[4];
  std::vector<Scored> scores_;
  std::vector<Slot> heap_;
  int keep_ = 16;
  bool keep_all_ = false;  // every candidate scored is kept (the search scores at most keep_)
  std::vector<int> last_coarse_;
  std::vector<int> near_;  // the candidates packed in near_diffuse_/near_specular_ (empty: none)
  std::size_t near_scored_ = 0;  // how many of near_ a near_last search scores (a prefix)
  int near_coarse_ = kCoarseTop, near_refits_ = 16;
  std::vector<float> near_diffuse_, near_specular_;
  std::vector<int> refit_;  // the scores_ to refit
  std::vector<float> refit_diffuse_, refit_specular_, refit_weights_;
  std::vector<float> zero_row_;        // k·kSearchLanes zeros: a padding lane's factors
  std::vector<int> excluded_;          // lights of the sums' base that the search leaves out
  std::vector<int> lit_;               // the usable lights
  int base_ = -1;                      // the sums' base (CandidateTable::base_sums)
  const double* base_from_ = nullptr;  // candidate c's sums in it at base_from_ + c·base_stride_
  std::ptrdiff_t base_stride_ = 0;
  bool from_table_ = true;          // sums from the base less excluded_, else summed directly
  std::vector<int> unlit_;          // the unusable lights
  std::vector<int> fold_unusable_;  // per fold, how many are unusable (zero between searches)
  std::vector<int> held_folds_;     // the folds of the unusable lights
};

// What a held-out fit does after the search on a fold's training lights: by default nothing (the
// winning candidate predicts the fold); the model choice refines the normal by the local fit
// (model_choice.cc), since a grid normal up to ~2° off penalizes sharp lobes for the grid alone.
class HeldOutRefiner {
 public:
  virtual ~HeldOutRefiner() = default;
  // The refined normal from the search's `start`, fitted to the lights where `training` is 1.
  virtual Vec3d Refine(const Vec3d& start, const double* training) = 0;
  // After Refine: the luminance the refined fit predicts for light j.
  virtual double Predicted(int j) const = 0;
};

// One pixel's held-out cost under a model, by cross-validation over the lights: for each fold f
// (fold[j] in 0 … F − 1) searched on the lights outside it (refined by `refiner` if given) and
// charged the censored cost of its own usable observations, in units of t², summed over the
// folds. normal[0] and normal[1] are the first two folds' normals (zero: none).
struct HeldOutResult {
  double cost = 0;
  Vec3d normal[2] = {Vec3d::Zero(), Vec3d::Zero()};
};
// `near_last`: the halves searched near the last full search of `search` (NormalSearch::Search).
// `per_light` (K, or nullptr): each light's own held-out cost, 0 where it is not usable, for a
// paired comparison of two models on the same lights (PairedDifference).
HeldOutResult HeldOutSearch(NormalSearch& search, const CandidateTable& table, const double* y,
                            const double* usable, const int* fold, double t,
                            std::vector<double>& buffer, bool near_last = false,
                            HeldOutRefiner* refiner = nullptr, double* per_light = nullptr);

// The same held-out cost without a search: each fold's normal is `refiner`'s refinement of one
// start (the pixel's normal from an earlier solve) on the fold's training lights. What a second
// pass costs when the first one has placed every pixel in its basin.
// With `censor_bright` a held-out observation brighter than predicted by more than t is censored
// too (the fit's PixelFitSettings::censor_bright).
HeldOutResult HeldOutFromStart(HeldOutRefiner& refiner, const Vec3d& start, int lights,
                               const double* y, const double* usable, const int* fold, double t,
                               std::vector<double>& buffer, double* per_light = nullptr,
                               bool censor_bright = false);

}  // namespace iphong::solve
