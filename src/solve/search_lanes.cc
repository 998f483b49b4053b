#include "solve/search_lanes.h"

#include <cstring>
#include <initializer_list>

// The bodies are inlined into one function per instruction set, which compiles them for it.
#define IPHONG_LANE_BODY static inline __attribute__((always_inline))

namespace iphong::solve::internal {
namespace {

typedef float Lanes __attribute__((vector_size(kLanes * sizeof(float))));

// N doubles (D), N floats (F) and a lane mask of N (M): the registers of the double-precision
// kernels, N = 2 for SSE2 and 4 for AVX2. Spelled out per N: GCC does not treat a vector type
// whose size depends on a template parameter as a vector everywhere.
template <int N>
struct Vec;
template <>
struct Vec<2> {
  typedef double D __attribute__((vector_size(16)));
  typedef float F __attribute__((vector_size(8)));
  typedef long long M __attribute__((vector_size(16)));
};
template <>
struct Vec<4> {
  typedef double D __attribute__((vector_size(32)));
  typedef float F __attribute__((vector_size(16)));
  typedef long long M __attribute__((vector_size(32)));
};

// Loads and stores through memcpy: the rows are 16-byte aligned, not 32.
inline void Load(Lanes* v, const float* p) { std::memcpy(v, p, sizeof(Lanes)); }
inline void Store(float* p, const Lanes& v) { std::memcpy(p, &v, sizeof(Lanes)); }

}  // namespace

// `product` and `cost` on B blocks for the same pixel at once: each block's accumulations are the
// single block's, in the same order, and the B chains of additions run side by side instead of
// one after another.
template <int B>
IPHONG_LANE_BODY void ProductBlocks(const float* const* diffuse, const float* const* specular,
                                    bool lobe, const int* lit, int n, const float* y,
                                    float* const* a_out, float* const* b_out) {
  Lanes a[B] = {}, b[B] = {}, row;
  if (lobe) {
    for (int t = 0; t < n; ++t) {
      const int j = lit[t];
      for (int q = 0; q < B; ++q) {
        Load(&row, diffuse[q] + j * kLanes);
        a[q] += y[j] * row;
        Load(&row, specular[q] + j * kLanes);
        b[q] += y[j] * row;
      }
    }
  } else {
    for (int t = 0; t < n; ++t) {
      const int j = lit[t];
      for (int q = 0; q < B; ++q) {
        Load(&row, diffuse[q] + j * kLanes);
        a[q] += y[j] * row;
      }
    }
  }
  for (int q = 0; q < B; ++q) {
    Store(a_out[q], a[q]);
    if (lobe) Store(b_out[q], b[q]);
  }
}

IPHONG_LANE_BODY void ProductBody(const float* diffuse, const float* specular, bool lobe,
                                  const int* lit, int n, const float* y, float* a_out,
                                  float* b_out) {
  ProductBlocks<1>(&diffuse, &specular, lobe, lit, n, y, &a_out, &b_out);
}

template <int B>
IPHONG_LANE_BODY void CostBlocks(const float* const* diffuse, const float* const* specular,
                                 bool lobe, const int* lit, int n, const float* y,
                                 const float* const* kd_in, const float* const* ks_in,
                                 float floor_in, float* const* cost_out,
                                 float* const* clipped_out) {
  const Lanes zero = {}, floor = zero + floor_in;
  Lanes kd[B], ks[B], d, s, cost[B] = {}, clipped[B] = {};
  for (int q = 0; q < B; ++q) {
    Load(&kd[q], kd_in[q]);
    Load(&ks[q], ks_in[q]);
  }
  for (int t = 0; t < n; ++t) {
    const int j = lit[t];
    for (int q = 0; q < B; ++q) {
      Load(&d, diffuse[q] + j * kLanes);
      Lanes r = y[j] - kd[q] * d;
      if (lobe) {
        Load(&s, specular[q] + j * kLanes);
        r -= ks[q] * s;
      }
      const Lanes under = floor - r;
      clipped[q] += under > zero ? under : zero;
      const Lanes kept = r > floor ? r : floor;
      cost[q] += kept * kept;
    }
  }
  for (int q = 0; q < B; ++q) {
    Store(cost_out[q], cost[q]);
    Store(clipped_out[q], clipped[q]);
  }
}

IPHONG_LANE_BODY void CostBody(const float* diffuse, const float* specular, bool lobe,
                               const int* lit, int n, const float* y, const float* kd_in,
                               const float* ks_in, float floor_in, float* cost_out,
                               float* clipped_out) {
  CostBlocks<1>(&diffuse, &specular, lobe, lit, n, y, &kd_in, &ks_in, floor_in, &cost_out,
                &clipped_out);
}

IPHONG_LANE_BODY void WeightedSumsBody(const float* diffuse, const float* specular, const int* lit,
                                       int n, const float* y, const float* kd_in,
                                       const float* ks_in, float floor_in, float* weights,
                                       float* sums, float* cost_out, float* changed_out) {
  const Lanes zero = {}, one = zero + 1.0f, floor = zero + floor_in;
  Lanes kd, ks, d, s, before;
  Load(&kd, kd_in);
  Load(&ks, ks_in);
  Lanes dd = {}, dx = {}, ss = {}, a = {}, b = {}, cost = {}, changed = {};
  for (int t = 0; t < n; ++t) {
    const int j = lit[t];
    Load(&d, diffuse + j * kLanes);
    Load(&s, specular + j * kLanes);
    const Lanes r = y[j] - kd * d - ks * s;
    const Lanes w = r >= floor ? one : zero;
    const Lanes kept = r > floor ? r : floor;
    cost += kept * kept;
    Load(&before, weights + j * kLanes);
    const Lanes difference = w - before;
    changed += difference > zero ? difference : -difference;
    Store(weights + j * kLanes, w);
    const Lanes wd = w * d, ws = w * s;
    dd += wd * d, dx += wd * s, ss += ws * s;
    a += wd * y[j], b += ws * y[j];
  }
  Store(sums, dd);
  Store(sums + kLanes, dx);
  Store(sums + 2 * kLanes, ss);
  Store(sums + 3 * kLanes, a);
  Store(sums + 4 * kLanes, b);
  if (cost_out) Store(cost_out, cost);
  if (changed_out) Store(changed_out, changed);
}

// internal::NonNegativePair with every branch computed and each lane's selected (a division by
// zero in a lane that does not take that branch is never selected), N lanes at a time: a vector
// as wide as the instruction set's registers, which GCC compares natively (a wider one it
// compares a lane at a time).
template <int N>
IPHONG_LANE_BODY void PairBody(const double* sums, double prior_weight, double prior_ks,
                               double ridge, const double* fixed_ks, double* kd_out,
                               double* ks_out) {
  typedef typename Vec<N>::D V;
  typedef typename Vec<N>::M M;  // a lane's mask
  static_assert(kLanes % N == 0, "whole registers");
  const V zero = {}, tiny_d = zero + 1e-12;
  for (int i = 0; i < kLanes; i += N) {
    V d, x, a, s, b;
    std::memcpy(&d, sums + i, sizeof d);
    std::memcpy(&x, sums + kLanes + i, sizeof x);
    std::memcpy(&s, sums + 2 * kLanes + i, sizeof s);
    std::memcpy(&a, sums + 3 * kLanes + i, sizeof a);
    std::memcpy(&b, sums + 4 * kLanes + i, sizeof b);
    V kd, ks;
    if (fixed_ks) {
      const V v = (a - *fixed_ks * x) / d;
      kd = d > tiny_d ? (zero < v ? v : zero) : zero;  // std::max(0.0, v)
      ks = zero + *fixed_ks;
    } else {
      s = s + prior_weight + ridge;
      b = b + prior_weight * prior_ks;
      const V det = d * s - x * x;
      const V least = 1e-9 * d * s;
      const V kd_free = (a * s - b * x) / det;
      const V ks_free = (b * d - a * x) / det;
      const M free = (det > least) & (d > tiny_d) & (kd_free >= zero) & (ks_free >= zero);
      bool all_free = true;
      for (int l = 0; l < N; ++l) all_free = all_free && free[l] != 0;
      if (all_free) {  // no lane takes the one-coefficient fits: their divisions are skipped
        std::memcpy(kd_out + i, &kd_free, sizeof kd_free);
        std::memcpy(ks_out + i, &ks_free, sizeof ks_free);
        continue;
      }
      const M diffuse_ok = (d > tiny_d) & (a > zero);
      const M specular_ok = (s > tiny_d) & (b > zero) & (det > least);
      const V gain_d = diffuse_ok ? a * a / d : zero;
      const V gain_s = specular_ok ? b * b / s : zero;
      const M lobe_wins = gain_s > gain_d;
      kd = free ? kd_free : ((diffuse_ok & ~lobe_wins) ? a / d : zero);
      ks = free ? ks_free : ((specular_ok & lobe_wins) ? b / s : zero);
    }
    std::memcpy(kd_out + i, &kd, sizeof kd);
    std::memcpy(ks_out + i, &ks, sizeof ks);
  }
}

// LaneKernels::pack: eight lights at a time as an 8 × 8 transpose in registers (three rounds of
// two-vector shuffles: pairs of 1, 2 and 4 lanes), the rest one by one.
IPHONG_LANE_BODY void PackBody(const float* const* rows, int k, float* out) {
  static_assert(kLanes == 8, "the transpose is 8 × 8");
  typedef int Index __attribute__((vector_size(kLanes * sizeof(int))));
  int j = 0;
  for (; j + kLanes <= k; j += kLanes) {
    Lanes r[kLanes], t[kLanes];
    for (int i = 0; i < kLanes; ++i) Load(&r[i], rows[i] + j);
    for (int i = 0; i < kLanes; i += 2) {
      t[i] = __builtin_shuffle(r[i], r[i + 1], Index{0, 8, 2, 10, 4, 12, 6, 14});
      t[i + 1] = __builtin_shuffle(r[i], r[i + 1], Index{1, 9, 3, 11, 5, 13, 7, 15});
    }
    for (const int i : {0, 1, 4, 5}) {
      r[i] = __builtin_shuffle(t[i], t[i + 2], Index{0, 1, 8, 9, 4, 5, 12, 13});
      r[i + 2] = __builtin_shuffle(t[i], t[i + 2], Index{2, 3, 10, 11, 6, 7, 14, 15});
    }
    for (int i = 0; i < 4; ++i) {
      t[i] = __builtin_shuffle(r[i], r[i + 4], Index{0, 1, 2, 3, 8, 9, 10, 11});
      t[i + 4] = __builtin_shuffle(r[i], r[i + 4], Index{4, 5, 6, 7, 12, 13, 14, 15});
    }
    for (int i = 0; i < kLanes; ++i) Store(out + (j + i) * kLanes, t[i]);
  }
  for (; j < k; ++j) {
    for (int i = 0; i < kLanes; ++i) out[j * kLanes + i] = rows[i][j];
  }
}

// The screening of B blocks (LaneKernels::score, score2, score4): the bodies above in sequence,
// with the sums in double N lanes at a time, each term as the scalar search computed it (d² as
// double(d)·double(d), an excluded light's subtracted as a sum of its negated term).
template <int N, int B>
IPHONG_LANE_BODY void ScoreBlocks(const float* const* diffuse, const float* const* specular,
                                  bool lobe, const int* lit, int n, const float* y,
                                  const double* const* base, const int* excluded, int n_excluded,
                                  const PairSettings& pair, float floor, BlockScore* out) {
  typedef typename Vec<N>::D V;
  typedef typename Vec<N>::F F;
  float a[B][kLanes], b[B][kLanes] = {};  // b stays 0 without a lobe
  float *a_at[B], *b_at[B];
  for (int q = 0; q < B; ++q) a_at[q] = a[q], b_at[q] = b[q];
  ProductBlocks<B>(diffuse, specular, lobe, lit, n, y, a_at, b_at);
  float kd[B][kLanes], ks[B][kLanes], *cost_at[B], *clipped_at[B];
  const float *kd_at[B], *ks_at[B];
  for (int q = 0; q < B; ++q) {
    double sums[5 * kLanes];
    for (int i = 0; i < kLanes; i += N) {
      V dd = {}, dx = {}, ss = {};
      F df, sf, af, bf;
      if (base[q]) {
        std::memcpy(&dd, base[q] + i, sizeof dd);
        std::memcpy(&dx, base[q] + kLanes + i, sizeof dx);
        std::memcpy(&ss, base[q] + 2 * kLanes + i, sizeof ss);
      }
      const int* lights = base[q] ? excluded : lit;
      const int count = base[q] ? n_excluded : n;
      const double sign = base[q] ? -1.0 : 1.0;
      for (int t = 0; t < count; ++t) {
        const int j = lights[t];
        std::memcpy(&df, diffuse[q] + j * kLanes + i, sizeof df);
        std::memcpy(&sf, specular[q] + j * kLanes + i, sizeof sf);
        const V d = __builtin_convertvector(df, V), s = __builtin_convertvector(sf, V);
        dd += sign * d * d, dx += sign * d * s, ss += sign * s * s;
      }
      std::memcpy(&af, a[q] + i, sizeof af);
      std::memcpy(&bf, b[q] + i, sizeof bf);
      const V ad = __builtin_convertvector(af, V), bd = __builtin_convertvector(bf, V);
      std::memcpy(sums + i, &dd, sizeof dd);
      std::memcpy(sums + kLanes + i, &dx, sizeof dx);
      std::memcpy(sums + 2 * kLanes + i, &ss, sizeof ss);
      std::memcpy(sums + 3 * kLanes + i, &ad, sizeof ad);
      std::memcpy(sums + 4 * kLanes + i, &bd, sizeof bd);
    }
    PairBody<N>(sums, pair.prior_weight, pair.prior_ks, pair.ridge, pair.fixed_ks, out[q].kd,
                out[q].ks);
    for (int i = 0; i < kLanes; i += N) {
      V kdd, ksd;
      std::memcpy(&kdd, out[q].kd + i, sizeof kdd);
      std::memcpy(&ksd, out[q].ks + i, sizeof ksd);
      const F kdf = __builtin_convertvector(kdd, F), ksf = __builtin_convertvector(ksd, F);
      std::memcpy(kd[q] + i, &kdf, sizeof kdf);
      std::memcpy(ks[q] + i, &ksf, sizeof ksf);
    }
    kd_at[q] = kd[q], ks_at[q] = ks[q];
    cost_at[q] = out[q].cost, clipped_at[q] = out[q].clipped;
  }
  CostBlocks<B>(diffuse, specular, lobe, lit, n, y, kd_at, ks_at, floor, cost_at, clipped_at);
}

template <int N>
IPHONG_LANE_BODY void ScoreBody(const float* diffuse, const float* specular, bool lobe,
                                const int* lit, int n, const float* y, const double* base,
                                const int* excluded, int n_excluded, const PairSettings& pair,
                                float floor, BlockScore* out) {
  ScoreBlocks<N, 1>(&diffuse, &specular, lobe, lit, n, y, &base, excluded, n_excluded, pair, floor,
                    out);
}

namespace {

// Each body compiled for the baseline and, on x86-64, for AVX2 (the target attribute compiles the
// inlined body for it).
void ProductBaseline(const float* diffuse, const float* specular, bool lobe, const int* lit, int n,
                     const float* y, float* a, float* b) {
  ProductBody(diffuse, specular, lobe, lit, n, y, a, b);
}
void CostBaseline(const float* diffuse, const float* specular, bool lobe, const int* lit, int n,
                  const float* y, const float* kd, const float* ks, float floor, float* cost,
                  float* clipped) {
  CostBody(diffuse, specular, lobe, lit, n, y, kd, ks, floor, cost, clipped);
}
void WeightedSumsBaseline(const float* diffuse, const float* specular, const int* lit, int n,
                          const float* y, const float* kd, const float* ks, float floor,
                          float* weights, float* sums, float* cost, float* changed) {
  WeightedSumsBody(diffuse, specular, lit, n, y, kd, ks, floor, weights, sums, cost, changed);
}
void PairBaseline(const double* sums, double prior_weight, double prior_ks, double ridge,
                  const double* fixed_ks, double* kd, double* ks) {
  PairBody<2>(sums, prior_weight, prior_ks, ridge, fixed_ks, kd, ks);
}
void ScoreBaseline(const float* diffuse, const float* specular, bool lobe, const int* lit, int n,
                   const float* y, const double* base, const int* excluded, int n_excluded,
                   const PairSettings& pair, float floor, BlockScore* out) {
  ScoreBody<2>(diffuse, specular, lobe, lit, n, y, base, excluded, n_excluded, pair, floor, out);
}

template <int B>
void ScoreManyBaseline(const float* const* diffuse, const float* const* specular, bool lobe,
                       const int* lit, int n, const float* y, const double* const* base,
                       const int* excluded, int n_excluded, const PairSettings& pair, float floor,
                       BlockScore* out) {
  ScoreBlocks<2, B>(diffuse, specular, lobe, lit, n, y, base, excluded, n_excluded, pair, floor,
                    out);
}

void PackBaseline(const float* const* rows, int k, float* out) { PackBody(rows, k, out); }

#if IPHONG_LANES_AVX2
__attribute__((target("avx2"))) void PackAvx2(const float* const* rows, int k, float* out) {
  PackBody(rows, k, out);
}
__attribute__((target("avx2"))) void ProductAvx2(const float* diffuse, const float* specular,
                                                 bool lobe, const int* lit, int n, const float* y,
                                                 float* a, float* b) {
  ProductBody(diffuse, specular, lobe, lit, n, y, a, b);
}
__attribute__((target("avx2"))) void CostAvx2(const float* diffuse, const float* specular,
                                              bool lobe, const int* lit, int n, const float* y,
                                              const float* kd, const float* ks, float floor,
                                              float* cost, float* clipped) {
  CostBody(diffuse, specular, lobe, lit, n, y, kd, ks, floor, cost, clipped);
}
__attribute__((target("avx2"))) void WeightedSumsAvx2(const float* diffuse, const float* specular,
                                                      const int* lit, int n, const float* y,
                                                      const float* kd, const float* ks, float floor,
                                                      float* weights, float* sums, float* cost,
                                                      float* changed) {
  WeightedSumsBody(diffuse, specular, lit, n, y, kd, ks, floor, weights, sums, cost, changed);
}
__attribute__((target("avx2"))) void PairAvx2(const double* sums, double prior_weight,
                                              double prior_ks, double ridge, const double* fixed_ks,
                                              double* kd, double* ks) {
  PairBody<4>(sums, prior_weight, prior_ks, ridge, fixed_ks, kd, ks);
}
__attribute__((target("avx2"))) void ScoreAvx2(const float* diffuse, const float* specular,
                                               bool lobe, const int* lit, int n, const float* y,
                                               const double* base, const int* excluded,
                                               int n_excluded, const PairSettings& pair,
                                               float floor, BlockScore* out) {
  ScoreBody<4>(diffuse, specular, lobe, lit, n, y, base, excluded, n_excluded, pair, floor, out);
}
template <int B>
__attribute__((target("avx2"))) void ScoreManyAvx2(const float* const* diffuse,
                                                   const float* const* specular, bool lobe,
                                                   const int* lit, int n, const float* y,
                                                   const double* const* base, const int* excluded,
                                                   int n_excluded, const PairSettings& pair,
                                                   float floor, BlockScore* out) {
  ScoreBlocks<4, B>(diffuse, specular, lobe, lit, n, y, base, excluded, n_excluded, pair, floor,
                    out);
}
#endif

}  // namespace

const LaneKernels& BaselineLaneKernels() {
  static const LaneKernels kernels{"baseline",           ProductBaseline,      CostBaseline,
                                   WeightedSumsBaseline, PairBaseline,         ScoreBaseline,
                                   ScoreManyBaseline<2>, ScoreManyBaseline<4>, PackBaseline};
  return kernels;
}

const LaneKernels* Avx2LaneKernels() {
#if IPHONG_LANES_AVX2
  static const LaneKernels kernels{"avx2",           ProductAvx2,      CostAvx2,
                                   WeightedSumsAvx2, PairAvx2,         ScoreAvx2,
                                   ScoreManyAvx2<2>, ScoreManyAvx2<4>, PackAvx2};
  static const bool available = __builtin_cpu_supports("avx2");
  return available ? &kernels : nullptr;
#else
  return nullptr;
#endif
}

const LaneKernels& SearchLaneKernels() {
  static const LaneKernels& kernels =
      Avx2LaneKernels() ? *Avx2LaneKernels() : BaselineLaneKernels();
  return kernels;
}

}  // namespace iphong::solve::internal
