// Many powers x_i^n of one constant exponent at once: the lobe's c^n for every light of a pixel
// (phong.h's ShadingFactorsOfLights). The model's LobePower takes exp(n·log c) one value at a
// time through glibc's scalar exp and log, about 15 ns a value here; glibc's own vector versions
// (libmvec, part of libc6: _ZGVdN4v_exp and _ZGVdN4v_log, four doubles a call with AVX2) take
// about 6. They are within a few units in the last place of the scalar functions, not equal
// to them: a power differs from LobePower's by about 1e-16·(1 + |n log c|) relative, ~1e-15 for
// a lobe value above 1e-6. Every value goes through the same four-wide call whatever its position
// or the count (the tail is padded), so a value's power does not depend on the other values beside
// it. Without AVX2 and FMA each value takes the scalar exp(n·log x), LobePower's own.
#pragma once

#include <cstddef>

namespace iphong::reflectance {

// out[i] = exp(exponent·log(base[i])) for i < count; each base > 0 and finite (the lobe's
// cosine where it is on), the exponent finite. out may alias base.
void ConstantPowers(const double* base, std::size_t count, double exponent, double* out);

// True where ConstantPowers takes libmvec's four-wide exp and log (AVX2 and FMA present).
bool ConstantPowersVectorized();

}  // namespace iphong::reflectance
