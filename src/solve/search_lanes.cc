#include "solve/search_lanes.h"

#include <cstring>

// The bodies are inlined into one function per instruction set, which compiles them for it.
#define IPHONG_LANE_BODY static inline __attribute__((always_inline))

namespace iphong::solve::internal {
namespace {

typedef float Lanes __attribute__((vector_size(kLanes * sizeof(float))));

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

#if IPHONG_LANES_AVX2
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
#endif

}  // namespace

const LaneKernels& BaselineLaneKernels() {
  static const LaneKernels kernels{"baseline", ProductBaseline, CostBaseline, WeightedSumsBaseline};
  return kernels;
}

const LaneKernels* Avx2LaneKernels() {
#if IPHONG_LANES_AVX2
  static const LaneKernels kernels{"avx2", ProductAvx2, CostAvx2, WeightedSumsAvx2};
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
