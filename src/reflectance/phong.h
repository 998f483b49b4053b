// The Phong reflection model, written once for every scalar type.
//
//   I = Ia ⊙ ka + Σ_lights [ Id ⊙ kd · (N·L) + Is ⊙ ks · (R·V)^n ],   R = 2(N·L)N − L,
//
// per RGB channel (⊙ is the channel-wise product), in the camera frame of core/types.h: N is
// the unit surface normal, L the unit direction from the surface toward the light, V the unit
// direction from the surface toward the viewer. Id and Is are the light's diffuse and specular
// intensities (seed 003's i_d and i_s; usually equal). Following seed 003, a term is included
// only where its dot product is positive, and the specular term only where N·L > 0.
// Blinn-Phong (seed 004) replaces (R·V)^n by (N·H)^n with H = (L + V)/|L + V|.
// The output is linear and unclamped.
//
// Every function is a template on the scalar T (double, float, ceres::Jet) so that the renderer,
// the Ceres solvers and the material fitter evaluate the very same code. Branches are on values
// only, and each branch is smooth, so Jet derivatives are defined wherever a solver can go.
// This header deliberately does not include Ceres: Jets are recognised by their shape.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <type_traits>
#include <vector>

#include "core/types.h"
#include "reflectance/powers.h"

namespace iphong::reflectance {

// Which specular lobe the model uses.
enum class Lobe {
  kPhong,       // (R·V)^n
  kBlinnPhong,  // (N·H)^n
  kLambert,     // no specular term
  // (N·L)^n: a sharpened diffuse term centred on the normal, not on the mirror direction. Not a
  // reflection model: the model choice's foil, a lobe of a highlight's width that follows the
  // normal, as irradiance fall-off or a non-Lambertian diffuse term does (solve/model_choice.h).
  kNormalCentred,
  // No specular term; the diffuse term is Oren and Nayar's for a rough surface (their qualitative
  // model, SIGGRAPH 1994) with the facets' slope σ (radians) in the shininess' place:
  // OrenNayarDiffuse. A matte surface of V-grooves: brighter than the cosine toward the view.
  kOrenNayar,
};

// How the power of the lobe is computed.
enum class PowerMode {
  // std::pow, or repeated squaring when the exponent is a constant integer (the same value,
  // several times faster; the exponent's derivative is zero there anyway).
  kExact,
  // Seed 003's approximation: max(0, c)^n ≈ max(0, 1 − βλ)^γ with γ = 2^k, β = n/γ and
  // λ = |R − V|²/2 (|N − H|²/2 for Blinn-Phong): k squarings, no pow, robust to normalization.
  kFastApprox,
};

struct ModelOptions {
  Lobe lobe = Lobe::kPhong;
  PowerMode power = PowerMode::kExact;
  int fast_approx_log2_gamma = 2;  // γ = 2^k; seed 003: "typically 4 will be enough"
};

// Material coefficients per RGB channel; shininess is the exponent n.
template <typename T>
struct MaterialT {
  Vec3T<T> ka = Vec3T<T>::Zero();
  Vec3T<T> kd = Vec3T<T>::Zero();
  Vec3T<T> ks = Vec3T<T>::Zero();
  T shininess = T(1);
};

namespace detail {

// A ceres::Jet has members `a` (value) and `v` (derivatives); recognise it without including Ceres.
template <typename T, typename = void>
struct IsJet : std::false_type {};
template <typename T>
struct IsJet<T, std::void_t<decltype(std::declval<T>().a), decltype(std::declval<T>().v)>>
    : std::true_type {};

// True (and *exponent set) when x is an integer constant small enough for repeated squaring:
// for a Jet its derivative part must be zero, otherwise d/dn is needed and pow must run.
template <typename T>
bool IsConstantInteger(const T& x, int* exponent) {
  if constexpr (IsJet<T>::value) {
    for (int i = 0; i < x.v.size(); ++i) {
      if (!(x.v[i] == 0)) return false;
    }
    return IsConstantInteger(x.a, exponent);
  } else {
    if (!(x >= T(0) && x <= T(1 << 16))) return false;
    const int n = static_cast<int>(x);
    if (static_cast<T>(n) != x) return false;
    *exponent = n;
    return true;
  }
}

// The view and light directions' type, kept out of template deduction: D is T unless a caller
// names it (ShadingFactors<Jet, double>), so Jet-cast expressions still convert as before.
template <typename D>
struct DirectionsOf {
  using type = Vec3T<D>;
};
template <typename D>
using Directions = typename DirectionsOf<D>::type;

// The value of a scalar: a Jet's `a`, a number itself.
template <typename T>
double ValueOf(const T& x) {
  if constexpr (IsJet<T>::value) {
    return static_cast<double>(x.a);
  } else {
    return static_cast<double>(x);
  }
}

// x^n for n ≥ 0 by repeated squaring.
template <typename T>
T IntegerPower(const T& x, int n) {
  T result = T(1);
  T base = x;
  while (n > 0) {
    if (n & 1) result = result * base;
    n >>= 1;
    if (n > 0) base = base * base;
  }
  return result;
}

}  // namespace detail

// The lobe's cosine c = R·V (Phong) or N·H (Blinn-Phong) raised to the shininess, for c > 0.
// `lambda` = |R − V|²/2 (or |N − H|²/2), equal to 1 − c for unit vectors; only the fast
// approximation uses it.
template <typename T>
T LobePower(const T& cosine, const T& lambda, const T& shininess, const ModelOptions& options) {
  using std::exp;
  using std::log;
  if (options.power == PowerMode::kFastApprox) {
    const int k = options.fast_approx_log2_gamma;
    const T beta = shininess / T(1 << k);
    T base = T(1) - beta * lambda;
    if (!(base > T(0))) return T(0);
    for (int i = 0; i < k; ++i) base = base * base;
    return base;
  }
  int n = 0;
  if (detail::IsConstantInteger(shininess, &n)) return detail::IntegerPower(cosine, n);
  // exp(n log c) keeps d/dn = c^n log c and d/dc = n c^(n−1) finite for every c > 0, n ≥ 0.
  return exp(shininess * log(cosine));
}

// The mirror image of the unit direction `v` about the unit normal, 2(N·v)N − v, given N·v: the
// model's R for v = L, and the light a mirror sphere shows at N for v = V (calibrate/).
template <typename T, typename V>
Vec3T<T> Reflect(const Vec3T<T>& normal_cam, const T& normal_dot_v, const V& v) {
  return T(2) * normal_dot_v * normal_cam - v;
}

// The lobe's cosine for one light whose N·L is n_dot_l > 0: R·V (Phong), N·H (Blinn-Phong) or
// N·L itself (the normal-centred foil); ≤ 0 where the lobe is off (and L = −V under Blinn-Phong,
// which leaves H undefined: no highlight can be seen there). `lambda` is the fast
// approximation's |R − V|²/2 (|N − H|²/2, 1 − N·L), 0 with the exact power. Only for the lobes
// that have one.
template <typename T>
struct LobeCosineOf {
  T cosine = T(0);
  T lambda = T(0);
};

template <typename T, typename D = T>
LobeCosineOf<T> LobeCosine(const Vec3T<T>& normal_cam, const detail::Directions<D>& view_cam,
                           const detail::Directions<D>& light_dir_cam, const T& n_dot_l,
                           const ModelOptions& options) {
  using std::sqrt;
  const bool fast = options.power == PowerMode::kFastApprox;
  LobeCosineOf<T> out;
  if (options.lobe == Lobe::kNormalCentred) {
    out.cosine = n_dot_l;
    if (fast) out.lambda = T(1) - n_dot_l;
    return out;
  }
  if (options.lobe == Lobe::kPhong) {
    const Vec3T<T> reflect_cam = Reflect(normal_cam, n_dot_l, light_dir_cam);
    out.cosine = reflect_cam.dot(view_cam);
    // λ feeds only the fast approximation; the exact power would waste a Jet product on it.
    if (fast && out.cosine > T(0)) out.lambda = T(0.5) * (reflect_cam - view_cam).squaredNorm();
    return out;
  }
  const Vec3T<D> sum = light_dir_cam + view_cam;
  const D sum_norm2 = sum.squaredNorm();
  if (!(sum_norm2 > D(1e-24))) return out;
  const Vec3T<D> half_cam = sum / sqrt(sum_norm2);
  out.cosine = normal_cam.dot(half_cam);
  if (fast && out.cosine > T(0)) out.lambda = T(0.5) * (normal_cam - half_cam).squaredNorm();
  return out;
}

// Oren and Nayar's qualitative diffuse factor for the facets' slope σ (radians):
//   cos θi·(A + B·max(0, cos(φi − φr))·sin α·tan β),  α = max(θi, θr), β = min(θi, θr),
//   A = 1 − σ²/(2(σ² + 0.33)),  B = 0.45 σ²/(σ² + 0.09),
// θi, θr the light's and the view's angles from N and φ their azimuths. In vectors, with
// sin θi sin θr cos(φi − φr) = L·V − (N·L)(N·V) and cos β = max(N·L, N·V), the B part is
// (N·L)·max(0, L·V − (N·L)(N·V)) / max(N·L, N·V): no trigonometry, and smooth where the
// trigonometric form's azimuth is undefined (N = V). σ = 0 is the cosine. Zero where N·L ≤ 0 or
// N·V ≤ 0 (a facet the camera cannot see reflects nothing toward it).
template <typename T, typename D = T>
T OrenNayarDiffuse(const Vec3T<T>& normal_cam, const detail::Directions<D>& view_cam,
                   const detail::Directions<D>& light_dir_cam, const T& slope) {
  const T n_dot_l = normal_cam.dot(light_dir_cam);
  if (!(n_dot_l > T(0))) return T(0);
  const T n_dot_v = normal_cam.dot(view_cam);
  if (!(n_dot_v > T(0))) return T(0);
  const T s2 = slope * slope;
  const T a = T(1) - T(0.5) * s2 / (s2 + T(0.33));
  const T b = T(0.45) * s2 / (s2 + T(0.09));
  const T spread = T(light_dir_cam.dot(view_cam)) - n_dot_l * n_dot_v;
  if (!(spread > T(0))) return a * n_dot_l;
  return n_dot_l * (a + b * spread / (n_dot_l > n_dot_v ? n_dot_l : n_dot_v));
}

// One light's two shading factors at a point, with seed 003's rules applied: diffuse = N·L where
// positive (else 0) and specular = the lobe (0 unless N·L > 0). A light contributes
// Id ⊙ kd · diffuse + Is ⊙ ks · specular; the albedo enters linearly, which is what lets the
// photometric-stereo solvers eliminate it in closed form.
template <typename T>
struct LightFactors {
  T diffuse = T(0);
  T specular = T(0);
};

// One light's factors up to the lobe's power, by those rules: the diffuse factor, and where the
// lobe is on (N·L > 0 and its cosine > 0) that cosine and λ, for LobePower to raise. Both
// ShadingFactors (one light) and ShadingFactorsOfLights (a batch of powers) start here.
template <typename T>
struct FactorsBeforePower {
  LightFactors<T> factors;  // specular still 0
  bool lobe = false;
  LobeCosineOf<T> lobe_cosine;
};

template <typename T, typename D = T>
FactorsBeforePower<T> ShadingFactorsBeforePower(const Vec3T<T>& normal_cam,
                                                const detail::Directions<D>& view_cam,
                                                const detail::Directions<D>& light_dir_cam,
                                                const T& shininess, const ModelOptions& options) {
  FactorsBeforePower<T> f;
  const T n_dot_l = normal_cam.dot(light_dir_cam);
  if (!(n_dot_l > T(0))) return f;
  if (options.lobe == Lobe::kOrenNayar) {
    f.factors.diffuse = OrenNayarDiffuse<T, D>(normal_cam, view_cam, light_dir_cam, shininess);
    return f;
  }
  f.factors.diffuse = n_dot_l;
  if (options.lobe == Lobe::kLambert) return f;
  f.lobe_cosine = LobeCosine<T, D>(normal_cam, view_cam, light_dir_cam, n_dot_l, options);
  f.lobe = f.lobe_cosine.cosine > T(0);
  return f;
}

template <typename T, typename D = T>
LightFactors<T> ShadingFactors(const Vec3T<T>& normal_cam, const detail::Directions<D>& view_cam,
                               const detail::Directions<D>& light_dir_cam, const T& shininess,
                               const ModelOptions& options) {
  FactorsBeforePower<T> f =
      ShadingFactorsBeforePower<T, D>(normal_cam, view_cam, light_dir_cam, shininess, options);
  if (f.lobe) {
    f.factors.specular = LobePower(f.lobe_cosine.cosine, f.lobe_cosine.lambda, shininess, options);
  }
  return f.factors;
}

// The specular lobe value (R·V)^n or (N·H)^n for one light, zero where seed 003's rules say so
// (N·L ≤ 0, or the lobe's cosine ≤ 0): ShadingFactors' specular factor. All vectors unit,
// camera frame. The view and light may have a plain scalar type D while the normal is a Jet
// (SpecularLobe<Jet, double>): constants then cost no derivative arithmetic (Ceres declares the
// mixed Eigen products).
template <typename T, typename D = T>
T SpecularLobe(const Vec3T<T>& normal_cam, const detail::Directions<D>& view_cam,
               const detail::Directions<D>& light_dir_cam, const T& shininess,
               const ModelOptions& options) {
  // Oren–Nayar has no lobe; its diffuse factor need not be computed to say so.
  if (options.lobe == Lobe::kOrenNayar) return T(0);
  return ShadingFactors<T, D>(normal_cam, view_cam, light_dir_cam, shininess, options).specular;
}

// ShadingFactorsOfLights' buffers, kept by the caller between calls (nothing allocated per call).
template <typename T>
struct LobeScratch {
  std::vector<T> cosine;
  std::vector<double> value;
  std::vector<int> light;
};

// ShadingFactors for every light j < count with use(j), into out[j] (the others are left as
// they are), at a constant shininess: each light's factors up to the power
// (ShadingFactorsBeforePower), then the lobes' powers c^n in one batch (powers.h's
// ConstantPowers: glibc's vector exp and log, within about 1e-15 relative of LobePower's scalar
// ones). A Jet's power carries LobePower's derivative n·c^n/c·dc. Where LobePower does not take
// exp(n log c) — an integer n (repeated squaring), the fast approximation — each light's power
// is LobePower's.
template <typename T, typename D, typename Use>
void ShadingFactorsOfLights(const Vec3T<T>& normal_cam, const detail::Directions<D>& view_cam,
                            const Vec3T<D>* light_dir_cam, int count, double shininess,
                            const ModelOptions& options, Use use, LobeScratch<T>& scratch,
                            LightFactors<T>* out) {
  const T n(shininess);
  int integer = 0;
  // exp(n log c) is LobePower's spelling only for the exact power of a non-integer n.
  const bool batch =
      options.power == PowerMode::kExact && !detail::IsConstantInteger(shininess, &integer);
  scratch.cosine.clear();
  scratch.value.clear();
  scratch.light.clear();
  for (int j = 0; j < count; ++j) {
    if (!use(j)) continue;
    const FactorsBeforePower<T> f =
        ShadingFactorsBeforePower<T, D>(normal_cam, view_cam, light_dir_cam[j], n, options);
    out[j] = f.factors;
    if (!f.lobe) continue;
    if (!batch) {
      out[j].specular = LobePower(f.lobe_cosine.cosine, f.lobe_cosine.lambda, n, options);
      continue;
    }
    scratch.cosine.push_back(f.lobe_cosine.cosine);
    scratch.value.push_back(detail::ValueOf(f.lobe_cosine.cosine));
    scratch.light.push_back(j);
  }
  if (scratch.light.empty()) return;
  ConstantPowers(scratch.value.data(), scratch.value.size(), shininess, scratch.value.data());
  for (std::size_t i = 0; i < scratch.light.size(); ++i) {
    const T& c = scratch.cosine[i];
    const double power = scratch.value[i], at = detail::ValueOf(c);
    // c^n + (c − c₀)·n·c₀^n/c₀: the value c₀^n, the derivative the chain rule's n·c^(n−1)·dc.
    out[scratch.light[i]].specular = T(power) + (c - T(at)) * (shininess * power / at);
  }
}

// One light's contribution from its factors: Id ⊙ kd · diffuse + Is ⊙ ks · specular. Solvers that
// keep the factors of a normal (to eliminate kd) combine them here instead of shading again.
template <typename T>
Vec3T<T> CombineFactors(const LightFactors<T>& f, const Vec3T<T>& diffuse_intensity,
                        const Vec3T<T>& specular_intensity, const Vec3T<T>& kd,
                        const Vec3T<T>& ks) {
  return diffuse_intensity.cwiseProduct(kd) * f.diffuse +
         specular_intensity.cwiseProduct(ks) * f.specular;
}

// One light's contribution Id ⊙ kd (N·L) + Is ⊙ ks · lobe, without the ambient term. This is the
// residual model of photometric stereo: image j is Ia ⊙ ka + LightTerm(L_j, E_j, E_j).
template <typename T>
Vec3T<T> LightTerm(const Vec3T<T>& normal_cam, const Vec3T<T>& view_cam,
                   const Vec3T<T>& light_dir_cam, const Vec3T<T>& diffuse_intensity,
                   const Vec3T<T>& specular_intensity, const MaterialT<T>& material,
                   const ModelOptions& options) {
  const LightFactors<T> f =
      ShadingFactors(normal_cam, view_cam, light_dir_cam, material.shininess, options);
  return CombineFactors(f, diffuse_intensity, specular_intensity, material.kd, material.ks);
}

// The ambient term Ia ⊙ ka.
template <typename T>
Vec3T<T> AmbientTerm(const Vec3T<T>& ambient_intensity, const MaterialT<T>& material) {
  return ambient_intensity.cwiseProduct(material.ka);
}

// Converts a material between scalar types (double → ceres::Jet, double → float).
template <typename To, typename From>
MaterialT<To> CastMaterial(const MaterialT<From>& m) {
  MaterialT<To> out;
  out.ka = m.ka.template cast<To>();
  out.kd = m.kd.template cast<To>();
  out.ks = m.ks.template cast<To>();
  out.shininess = To(m.shininess);
  return out;
}

}  // namespace iphong::reflectance
