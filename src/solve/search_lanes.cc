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

// The baseline's and AVX2's compilations of each body, and the dispatch between them.
void ProductLanesBaseline(const float* diffuse, const float* specular, bool lobe, const int* lit,
                          int n, const float* y, float* a, float* b) {
  ProductBody(diffuse, specular, lobe, lit, n, y, a, b);
}
void CostLanesBaseline(const float* diffuse, const float* specular, bool lobe, const int* lit,
                       int n, const float* y, const float* kd, const float* ks, float floor,
                       float* cost, float* clipped) {
  CostBody(diffuse, specular, lobe, lit, n, y, kd, ks, floor, cost, clipped);
}
void WeightedSumsLanesBaseline(const float* diffuse, const float* specular, const int* lit, int n,
                               const float* y, const float* kd, const float* ks, float floor,
                               float* weights, float* sums, float* cost, float* changed) {
  WeightedSumsBody(diffuse, specular, lit, n, y, kd, ks, floor, weights, sums, cost, changed);
}

#if IPHONG_LANES_AVX2
__attribute__((target("avx2"))) void ProductLanesAvx2(const float* diffuse, const float* specular,
                                                      bool lobe, const int* lit, int n,
                                                      const float* y, float* a, float* b) {
  ProductBody(diffuse, specular, lobe, lit, n, y, a, b);
}
__attribute__((target("avx2"))) void CostLanesAvx2(const float* diffuse, const float* specular,
                                                   bool lobe, const int* lit, int n, const float* y,
                                                   const float* kd, const float* ks, float floor,
                                                   float* cost, float* clipped) {
  CostBody(diffuse, specular, lobe, lit, n, y, kd, ks, floor, cost, clipped);
}
__attribute__((target("avx2"))) void WeightedSumsLanesAvx2(const float* diffuse,
                                                           const float* specular, const int* lit,
                                                           int n, const float* y, const float* kd,
                                                           const float* ks, float floor,
                                                           float* weights, float* sums, float* cost,
                                                           float* changed) {
  WeightedSumsBody(diffuse, specular, lit, n, y, kd, ks, floor, weights, sums, cost, changed);
}
#endif

bool LanesUseAvx2() {
#if IPHONG_LANES_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
#else
  return false;
#endif
}

void ProductLanes(const float* diffuse, const float* specular, bool lobe, const int* lit, int n,
                  const float* y, float* a, float* b) {
#if IPHONG_LANES_AVX2
  if (LanesUseAvx2()) return ProductLanesAvx2(diffuse, specular, lobe, lit, n, y, a, b);
#endif
  ProductLanesBaseline(diffuse, specular, lobe, lit, n, y, a, b);
}

void CostLanes(const float* diffuse, const float* specular, bool lobe, const int* lit, int n,
               const float* y, const float* kd, const float* ks, float floor, float* cost,
               float* clipped) {
#if IPHONG_LANES_AVX2
  if (LanesUseAvx2()) {
    return CostLanesAvx2(diffuse, specular, lobe, lit, n, y, kd, ks, floor, cost, clipped);
  }
#endif
  CostLanesBaseline(diffuse, specular, lobe, lit, n, y, kd, ks, floor, cost, clipped);
}

void WeightedSumsLanes(const float* diffuse, const float* specular, const int* lit, int n,
                       const float* y, const float* kd, const float* ks, float floor,
                       float* weights, float* sums, float* cost, float* changed) {
#if IPHONG_LANES_AVX2
  if (LanesUseAvx2()) {
    return WeightedSumsLanesAvx2(diffuse, specular, lit, n, y, kd, ks, floor, weights, sums, cost,
                                 changed);
  }
#endif
  WeightedSumsLanesBaseline(diffuse, specular, lit, n, y, kd, ks, floor, weights, sums, cost,
                            changed);
}

}  // namespace iphong::solve::internal
