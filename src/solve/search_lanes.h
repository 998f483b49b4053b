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

// The three loops, compiled for one instruction set.
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
};

// The baseline's kernels, AVX2's (nullptr off x86-64 or where the processor lacks AVX2), and the
// ones the search runs: AVX2's where there are any.
const LaneKernels& BaselineLaneKernels();
const LaneKernels* Avx2LaneKernels();
const LaneKernels& SearchLaneKernels();

}  // namespace iphong::solve::internal
