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

IPHONG_LANE_BODY void ProductBody(const float* diffuse, const float* specular, bool lobe,
                                  const int* lit, int n, const float* y, float* a_out,
                                  float* b_out) {
  Lanes a = {}, b = {}, row;
  for (int t = 0; t < n; ++t) {
    const int j = lit[t];
    Load(&row, diffuse + j * kLanes);
    a += y[j] * row;
  }
  Store(a_out, a);
  if (!lobe) return;
  for (int t = 0; t < n; ++t) {
    const int j = lit[t];
    Load(&row, specular + j * kLanes);
    b += y[j] * row;
  }
  Store(b_out, b);
}

IPHONG_LANE_BODY void CostBody(const float* diffuse, const float* specular, bool lobe,
                               const int* lit, int n, const float* y, const float* kd_in,
                               const float* ks_in, float floor_in, float* cost_out,
                               float* clipped_out) {
  const Lanes zero = {}, floor = zero + floor_in;
  Lanes kd, ks, d, s, cost = {}, clipped = {};
  Load(&kd, kd_in);
  Load(&ks, ks_in);
  for (int t = 0; t < n; ++t) {
    const int j = lit[t];
    Load(&d, diffuse + j * kLanes);
    Lanes r = y[j] - kd * d;
    if (lobe) {
      Load(&s, specular + j * kLanes);
      r -= ks * s;
    }
    const Lanes under = floor - r;
    clipped += under > zero ? under : zero;
    const Lanes kept = r > floor ? r : floor;
    cost += kept * kept;
  }
  Store(cost_out, cost);
  Store(clipped_out, clipped);
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

// The screening of one block (LaneKernels::score): the bodies above in sequence, with the sums in
// double N lanes at a time, each term as the scalar search computed it (d² as double(d)·double(d),
// an excluded light's subtracted as a sum of its negated term).
template <int N>
IPHONG_LANE_BODY void ScoreBody(const float* diffuse, const float* specular, bool lobe,
                                const int* lit, int n, const float* y, const double* base,
                                const int* excluded, int n_excluded, const PairSettings& pair,
                                float floor, BlockScore* out) {
  typedef typename Vec<N>::D V;
  typedef typename Vec<N>::F F;
  float a[kLanes], b[kLanes] = {};  // b stays 0 without a lobe
  ProductBody(diffuse, specular, lobe, lit, n, y, a, b);
  double sums[5 * kLanes];
  for (int i = 0; i < kLanes; i += N) {
    V dd = {}, dx = {}, ss = {};
    F df, sf, af, bf;
    if (base) {
      std::memcpy(&dd, base + i, sizeof dd);
      std::memcpy(&dx, base + kLanes + i, sizeof dx);
      std::memcpy(&ss, base + 2 * kLanes + i, sizeof ss);
    }
    const int* lights = base ? excluded : lit;
    const int count = base ? n_excluded : n;
    const double sign = base ? -1.0 : 1.0;
    for (int t = 0; t < count; ++t) {
      const int j = lights[t];
      std::memcpy(&df, diffuse + j * kLanes + i, sizeof df);
      std::memcpy(&sf, specular + j * kLanes + i, sizeof sf);
      const V d = __builtin_convertvector(df, V), s = __builtin_convertvector(sf, V);
      dd += sign * d * d, dx += sign * d * s, ss += sign * s * s;
    }
    std::memcpy(&af, a + i, sizeof af);
    std::memcpy(&bf, b + i, sizeof bf);
    const V ad = __builtin_convertvector(af, V), bd = __builtin_convertvector(bf, V);
    std::memcpy(sums + i, &dd, sizeof dd);
    std::memcpy(sums + kLanes + i, &dx, sizeof dx);
    std::memcpy(sums + 2 * kLanes + i, &ss, sizeof ss);
    std::memcpy(sums + 3 * kLanes + i, &ad, sizeof ad);
    std::memcpy(sums + 4 * kLanes + i, &bd, sizeof bd);
  }
  PairBody<N>(sums, pair.prior_weight, pair.prior_ks, pair.ridge, pair.fixed_ks, out->kd, out->ks);
  float kd[kLanes], ks[kLanes];
  for (int i = 0; i < kLanes; i += N) {
    V kdd, ksd;
    std::memcpy(&kdd, out->kd + i, sizeof kdd);
    std::memcpy(&ksd, out->ks + i, sizeof ksd);
    const F kdf = __builtin_convertvector(kdd, F), ksf = __builtin_convertvector(ksd, F);
    std::memcpy(kd + i, &kdf, sizeof kdf);
    std::memcpy(ks + i, &ksf, sizeof ksf);
  }
  CostBody(diffuse, specular, lobe, lit, n, y, kd, ks, floor, out->cost, out->clipped);
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
#endif

}  // namespace

const LaneKernels& BaselineLaneKernels() {
  static const LaneKernels kernels{"baseline",           ProductBaseline, CostBaseline,
                                   WeightedSumsBaseline, PairBaseline,    ScoreBaseline,
                                   PackBaseline};
  return kernels;
}

const LaneKernels* Avx2LaneKernels() {
#if IPHONG_LANES_AVX2
  static const LaneKernels kernels{"avx2",   ProductAvx2, CostAvx2, WeightedSumsAvx2,
                                   PairAvx2, ScoreAvx2,   PackAvx2};
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
