// The search's inner loops (solve/search.h), on one packed block of kLanes candidates: each light
// j's factors for the block's candidates are kLanes contiguous floats at rows + j·kLanes, and a
// loop runs over the pixel's usable lights `lit` (n of them) with the candidates in vector lanes.
// Written once with GCC's vector types; on x86-64 each is compiled twice, for AVX2 (one 256-bit
// operation per light) and for the baseline (two SSE2 operations); the search runs the one the
// processor can. Neither contracts a·b + c into one rounding (AVX2 without FMA), so both
// give the same bits (a test compares them).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__)
#define IPHONG_LANES_AVX2 1
#else
#define IPHONG_LANES_AVX2 0
#endif

namespace iphong::solve::internal {

constexpr int kLanes = 8;

// What the screening of one block needs besides its factors and the pixel: the 2 × 2 solve's
// prior and ridge (internal::NonNegativePair), or a fixed ks.
struct PairSettings {
  double prior_weight = 0, prior_ks = 0, ridge = 0;
  const double* fixed_ks = nullptr;
};
// The screening's result for kLanes candidates.
struct BlockScore {
  float cost[kLanes], clipped[kLanes];  // as `cost` below gives them, at (kd, ks) in float
  double kd[kLanes], ks[kLanes];        // the non-negative least squares (`pair`)
};

// The kernels, compiled for one instruction set.
struct LaneKernels {
  const char* name;
  // a = Σ_j y_j d_j and, with `lobe`, b = Σ_j y_j s_j (else b is left alone).
  void (*product)(const float* diffuse, const float* specular, bool lobe, const int* lit, int n,
                  const float* y, float* a, float* b);
  // cost = Σ_j max(r_j, floor)², clipped = Σ_j max(floor − r_j, 0) with r_j = y_j − kd d_j − ks s_j
  // (ks s_j only with `lobe`): the censored cost and by how much the censoring clips.
  void (*cost)(const float* diffuse, const float* specular, bool lobe, const int* lit, int n,
               const float* y, const float* kd, const float* ks, float floor, float* cost,
               float* clipped);
  // The censoring's weights w_j = [r_j ≥ floor] at (kd, ks), written to weights[j·kLanes …], and
  // the weighted sums Σ w d², Σ w d s, Σ w s², Σ w d y, Σ w s y into sums[0 … 4] (kLanes each).
  // With `cost` (or nullptr), the censored cost at (kd, ks) as `cost` above gives it; with
  // `changed`, Σ_j |w_j − the weight weights held before|.
  void (*weighted_sums)(const float* diffuse, const float* specular, const int* lit, int n,
                        const float* y, const float* kd, const float* ks, float floor,
                        float* weights, float* sums, float* cost, float* changed);
  // internal::NonNegativePair of kLanes systems, one a lane, from sums[0 … 4] (kLanes each:
  // D, X, S, A, B) with the prior (prior_weight, prior_ks) and the ridge; with `fixed_ks`
  // (non-null) kd alone, clamped at 0, and ks = *fixed_ks. Every branch is computed and the
  // lane's chosen, the same operations in the same order: the same bits as the scalar function.
  void (*pair)(const double* sums, double prior_weight, double prior_ks, double ridge,
               const double* fixed_ks, double* kd, double* ks);
  // The screening of one block, `product`, `pair` and `cost` in one pass: a = Σ y d, b = Σ y s
  // over the lit lights (float), the 2 × 2 system's Σ d², Σ d s, Σ s² in double — from `base`
  // (3 × kLanes, those sums over a larger set of lights) less the terms of the `excluded`
  // lights, or summed over the lit lights where `base` is null — the pair at them, and the
  // censored cost at that pair rounded to float.
  void (*score)(const float* diffuse, const float* specular, bool lobe, const int* lit, int n,
                const float* y, const double* base, const int* excluded, int n_excluded,
                const PairSettings& pair, float floor, BlockScore* out);
  // `score` on two and on four blocks for the same pixel (diffuse[q], specular[q], base[q] and
  // out[q] for block q): each block's result is `score`'s on it, the blocks computed side by side
  // (one block's sums are a chain of additions, each waiting on the last).
  using ScoreMany = void (*)(const float* const* diffuse, const float* const* specular, bool lobe,
                             const int* lit, int n, const float* y, const double* const* base,
                             const int* excluded, int n_excluded, const PairSettings& pair,
                             float floor, BlockScore* out);
  ScoreMany score2, score4;
  // A block packed from kLanes rows of k floats each: out[j·kLanes + i] = rows[i][j] (a copy).
  void (*pack)(const float* const* rows, int k, float* out);
};

// The baseline's kernels, AVX2's (nullptr off x86-64 or where the processor lacks AVX2), and the
// ones the search runs: AVX2's where there are any.
const LaneKernels& BaselineLaneKernels();
const LaneKernels* Avx2LaneKernels();
const LaneKernels& SearchLaneKernels();

}  // namespace iphong::solve::internal
