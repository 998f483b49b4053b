#include "reflectance/powers.h"

#include <immintrin.h>

#include <cmath>

// glibc's vector math (libmvec, linked through libm's AS_NEEDED entry): the AVX2 variants of
// exp and log, four doubles a call. Declared here because <math.h> declares them only to the
// compiler's auto-vectorizer, under -ffast-math.
extern "C" __m256d _ZGVdN4v_exp(__m256d);
extern "C" __m256d _ZGVdN4v_log(__m256d);

namespace iphong::reflectance {
namespace {

__attribute__((target("avx2,fma"))) void PowersAvx2(const double* base, std::size_t count,
                                                    double exponent, double* out) {
  const __m256d n = _mm256_set1_pd(exponent);
  std::size_t i = 0;
  for (; i + 4 <= count; i += 4) {
    const __m256d x = _mm256_loadu_pd(base + i);
    _mm256_storeu_pd(out + i, _ZGVdN4v_exp(_mm256_mul_pd(n, _ZGVdN4v_log(x))));
  }
  if (i == count) return;
  // The tail padded with ones through the same call: a value's power never depends on where it
  // sits in the batch.
  alignas(32) double tail[4] = {1, 1, 1, 1};
  for (std::size_t t = 0; i + t < count; ++t) tail[t] = base[i + t];
  _mm256_store_pd(tail, _ZGVdN4v_exp(_mm256_mul_pd(n, _ZGVdN4v_log(_mm256_load_pd(tail)))));
  for (std::size_t t = 0; i + t < count; ++t) out[i + t] = tail[t];
}

bool Vectorized() {
  static const bool available = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return available;
}

}  // namespace

void ConstantPowers(const double* base, std::size_t count, double exponent, double* out) {
  if (Vectorized()) {
    PowersAvx2(base, count, exponent, out);
    return;
  }
  for (std::size_t i = 0; i < count; ++i) out[i] = std::exp(exponent * std::log(base[i]));
}

}  // namespace iphong::reflectance
