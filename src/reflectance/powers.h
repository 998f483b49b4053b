// Many powers x_i^n of one constant exponent at once: the lobe's c^n for every light of a pixel
// (phong.h's ShadingFactorsOfLights), where the model's LobePower takes exp(n·log c) one value
// at a time. Written here because the scalar exp and log are a large share of the local fit and
// glibc has their vector versions (libmvec, part of libc6: _ZGVdN4v_exp and _ZGVdN4v_log, four
// doubles a call with AVX2; docs/benchmarks.md has the figures). They are within a few units in
// the last place of the scalar functions, not equal to them: a power differs from LobePower's by
// about 1e-16·(1 + |n log c|) relative. Every value goes through the same four-wide call whatever
// its position or the count (the tail is padded), so a value's power does not depend on the
// values beside it. Without AVX2 and FMA each value takes the scalar exp(n·log x), LobePower's.
#pragma once

#include <cstddef>

namespace iphong::reflectance {

// out[i] = exp(exponent·log(base[i])) for i < count; each base > 0 and finite (the lobe's
// cosine where it is on), the exponent finite. out may alias base.
void ConstantPowers(const double* base, std::size_t count, double exponent, double* out);

}  // namespace iphong::reflectance
