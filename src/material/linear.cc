// The linear part of the material fit: for a fixed shininess every coefficient enters linearly,
// so the albedos are eliminated in closed form and the shininess is found by a 1-D search of
// the profile cost, which has no local minimum to fall into at the grid's spacing.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

#include "core/parallel.h"
#include "material/internal.h"
#include "solve/internal.h"
#include "solve/photometric_data.h"

namespace iphong::material::internal {

using reflectance::Lobe;

Sample BuildSample(const solve::PhotometricData& data, const std::vector<Vec3d>& normals_cam,
                   const MaterialFitOptions& options, std::vector<std::size_t>* with_normal,
                   std::vector<int>* group_of) {
  const std::size_t count = data.pixel_count();
  with_normal->clear();
  group_of->assign(count, -1);
  // Region labels are renumbered 0..R−1 in order of value, so groups are dense.
  std::map<int, int> region_group;
  for (std::size_t p = 0; p < count; ++p) {
    if (normals_cam[p].squaredNorm() == 0) continue;
    if (options.albedo == AlbedoMode::kPerRegion) {
      if (options.region[p] < 0) continue;
      region_group.emplace(options.region[p], 0);
    }
    with_normal->push_back(p);
  }
  if (with_normal->empty()) {
    throw std::invalid_argument("no pixel has both a normal and an observation");
  }
  int next = 0;
  for (auto& [label, g] : region_group) g = next++;
  for (std::size_t i = 0; i < with_normal->size(); ++i) {
    const std::size_t p = (*with_normal)[i];
    (*group_of)[p] = options.albedo == AlbedoMode::kPerPixel  ? static_cast<int>(i)
                     : options.albedo == AlbedoMode::kUniform ? 0
                                                              : region_group[options.region[p]];
  }

  Sample s;
  s.data = &data;
  s.lights = data.images;
  s.threads = options.threads;
  const std::size_t stride =
      (with_normal->size() + options.max_pixels - 1) / static_cast<std::size_t>(options.max_pixels);
  for (std::size_t i = 0; i < with_normal->size(); i += stride) {
    const std::size_t p = (*with_normal)[i];
    s.pixel.push_back(p);
    s.normal.push_back(normals_cam[p]);
    s.group.push_back(options.albedo == AlbedoMode::kPerPixel ? static_cast<int>(s.pixel.size()) - 1
                                                              : (*group_of)[p]);
  }
  s.groups = options.albedo == AlbedoMode::kPerPixel  ? static_cast<int>(s.pixel.size())
             : options.albedo == AlbedoMode::kUniform ? 1
                                                      : static_cast<int>(region_group.size());

  FillFactors(s, options.saturation, options.shadow_threshold, options.threads);
  return s;
}

void FillFactors(Sample& s, double saturation, double shadow_threshold, int threads) {
  const solve::PhotometricData& data = *s.data;
  const int k = data.images;
  const std::size_t n = s.pixel.size() * k;
  s.diffuse.assign(n, 0);
  s.cos_phong.assign(n, 0);
  s.cos_blinn.assign(n, 0);
  s.usable.assign(n, 0);
  s.threshold.assign(s.pixel.size(), Vec3d::Zero());
  const Vec3d view = solve::internal::ViewCam();
  reflectance::ModelOptions phong, blinn;
  blinn.lobe = Lobe::kBlinnPhong;
  ParallelFor(0, s.pixel.size(), 256, threads, [&](std::size_t b, std::size_t e) {
    std::array<std::vector<double>, 3> values;
    for (std::size_t p = b; p < e; ++p) {
      const Vec3d normal = s.normal[p];
      for (auto& v : values) v.clear();
      const double level = solve::PixelSaturation(s.y(p, 0), 3 * std::size_t(k), saturation);
      for (int j = 0; j < k; ++j) {
        const std::size_t i = p * k + j;
        const Vec3d& light = data.light_directions[j];
        // The shared model's factors with n = 1 are the lobe's cosine itself.
        const reflectance::LightFactors<double> f =
            reflectance::ShadingFactors(normal, view, light, 1.0, phong);
        s.diffuse[i] = f.diffuse;
        s.cos_phong[i] = f.specular;
        s.cos_blinn[i] = reflectance::SpecularLobe(normal, view, light, 1.0, blinn);
        const float* y = s.y(p, j);
        bool ok = true;
        for (int ch = 0; ch < 3; ++ch) ok = ok && std::isfinite(y[ch]) && y[ch] < level;
        s.usable[i] = ok;
        if (ok) {
          for (int ch = 0; ch < 3; ++ch) values[ch].push_back(y[ch]);
        }
      }
      for (int ch = 0; ch < 3; ++ch) {
        s.threshold[p][ch] = shadow_threshold * solve::internal::BrightnessScale(values[ch]);
      }
    }
  });
}

double LobeFactor(double cosine, double shininess) {
  return cosine > 0 ? reflectance::LobePower(cosine, 0.0, shininess, reflectance::ModelOptions{})
                    : 0.0;
}

namespace {

// The sufficient statistics of one shininess, per channel c: per group D = Σ(e d)², X1 = Σ e d,
// Xs = Σ (e d)(e s), Y = Σ e d y (entries 4c..4c+3), and over everything n, Σ e s, Σ (e s)²,
// Σ y, Σ e s y, Σ y².
struct Sums {
  std::vector<std::array<double, 12>> group;
  std::array<double, 3> n1{}, s1{}, ss{}, y1{}, ys{}, yy{};
};

// Adds `from` into `to`.
void Add(const Sums& from, Sums& to) {
  for (std::size_t g = 0; g < to.group.size(); ++g)
    for (int i = 0; i < 12; ++i) to.group[g][i] += from.group[g][i];
  for (int c = 0; c < 3; ++c) {
    to.n1[c] += from.n1[c], to.s1[c] += from.s1[c], to.ss[c] += from.ss[c];
    to.y1[c] += from.y1[c], to.ys[c] += from.ys[c], to.yy[c] += from.yy[c];
  }
}

// `range(begin, end, part)` over the sample's pixels, one contiguous part per thread, each into
// its own zeroed sums; returns their total.
template <typename Range>
Sums SumInParts(const Sample& s, Range range) {
  const std::size_t parts =
      std::min<std::size_t>(ResolveThreads(s.threads), std::max<std::size_t>(1, s.size() / 512));
  std::vector<Sums> partial(parts);
  ParallelFor(0, parts, 1, static_cast<int>(parts), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      partial[t].group.assign(s.groups, {});
      range(s.size() * t / parts, s.size() * (t + 1) / parts, partial[t]);
    }
  });
  for (std::size_t t = 1; t < parts; ++t) Add(partial[t], partial[0]);
  return std::move(partial[0]);
}

// The sums that do not depend on the lobe: D, X1, Y per group; n, Σ y, Σ y².
Sums BaseSums(const Sample& s, const std::vector<unsigned char>& used) {
  return SumInParts(s, [&](std::size_t begin, std::size_t end, Sums& sums) {
    const int k = s.lights;
    for (std::size_t p = begin; p < end; ++p) {
      std::array<double, 12>& gp = sums.group[s.group[p]];
      for (int j = 0; j < k; ++j) {
        const std::size_t i = p * k + j;
        if (!used[i]) continue;
        const float* y = s.y(p, j);
        const Vec3d& e = s.data->light_intensities[j];
        for (int c = 0; c < 3; ++c) {
          const double d = e[c] * s.diffuse[i];
          gp[4 * c] += d * d;
          gp[4 * c + 1] += d;
          gp[4 * c + 3] += d * y[c];
          sums.n1[c] += 1;
          sums.y1[c] += y[c];
          sums.yy[c] += double(y[c]) * y[c];
        }
      }
    }
  });
}

// The lobe's sums for one shininess: Xs per group; Σ e s, Σ (e s)², Σ e s y. Only observations
// with a lobe enter: where c^n < 1e-16 it is below double precision against ks and its power is
// not taken (on a sharp lobe, most observations).
Sums LobeSums(const Sample& s, Lobe lobe, double shininess,
              const std::vector<unsigned char>& used) {
  const double negligible = std::exp(std::log(1e-16) / std::max(shininess, 1e-3));
  return SumInParts(s, [&](std::size_t begin, std::size_t end, Sums& sums) {
    const int k = s.lights;
    for (std::size_t p = begin; p < end; ++p) {
      std::array<double, 12>& gp = sums.group[s.group[p]];
      for (int j = 0; j < k; ++j) {
        const std::size_t i = p * k + j;
        const double cosine = s.cosine(lobe, i);
        if (!used[i] || !(cosine > negligible)) continue;
        const double lobe_factor = LobeFactor(cosine, shininess);
        const float* y = s.y(p, j);
        const Vec3d& e = s.data->light_intensities[j];
        for (int c = 0; c < 3; ++c) {
          const double d = e[c] * s.diffuse[i], sp = e[c] * lobe_factor;
          gp[4 * c + 2] += d * sp;
          sums.s1[c] += sp;
          sums.ss[c] += sp * sp;
          sums.ys[c] += sp * y[c];
        }
      }
    }
  });
}

// A group whose observations barely see its light (D ≈ 0) leaves its kd undetermined.
constexpr double kMinD = 1e-8;

// kd_g = (Y − a X1 − ks Xs) / D, the least-squares albedo given (a, ks).
void SolveAlbedos(const Sums& sums, Coefficients* out) {
  const int groups = static_cast<int>(sums.group.size());
  out->kd.assign(groups, Vec3d::Zero());
  out->kd_known.assign(groups, 0);
  for (int grp = 0; grp < groups; ++grp) {
    const auto& gp = sums.group[grp];
    for (int c = 0; c < 3; ++c) {
      const double d = gp[4 * c];
      if (!(d > kMinD)) continue;
      out->kd[grp][c] =
          (gp[4 * c + 3] - out->ambient[c] * gp[4 * c + 1] - out->ks[c] * gp[4 * c + 2]) / d;
      out->kd_known[grp] = 1;
    }
  }
}

// The least-squares coefficients from the sums of one shininess (LinearFit).
Coefficients Solve(const Sums& sums, bool specular, double shininess) {
  Coefficients out;
  out.shininess = specular ? shininess : 0;
  for (int c = 0; c < 3; ++c) {
    // Reduced normal equations of (a, ks): M θ = r.
    double m00 = sums.n1[c], m01 = sums.s1[c], m11 = sums.ss[c], r0 = sums.y1[c], r1 = sums.ys[c],
           explained = 0;
    for (const auto& gp : sums.group) {
      const double d = gp[4 * c];
      if (!(d > kMinD)) continue;
      const double x1 = gp[4 * c + 1], xs = gp[4 * c + 2], y = gp[4 * c + 3];
      m00 -= x1 * x1 / d;
      m01 -= x1 * xs / d;
      m11 -= xs * xs / d;
      r0 -= y * x1 / d;
      r1 -= y * xs / d;
      explained += y * y / d;
    }
    // The non-negative minimum of f(θ) = θᵀMθ − 2rᵀθ: the free solution if feasible, else the
    // best one-coefficient or zero solution. RSS = Σy² − Σ_g Y²/D + f(θ).
    auto f = [&](double a, double ks) {
      return m00 * a * a + 2 * m01 * a * ks + m11 * ks * ks - 2 * (r0 * a + r1 * ks);
    };
    double best_a = 0, best_ks = 0, best_f = 0;
    auto consider = [&](double a, double ks) {
      if (a < 0 || ks < 0 || !std::isfinite(a) || !std::isfinite(ks)) return;
      const double v = f(a, ks);
      if (v < best_f) best_a = a, best_ks = ks, best_f = v;
    };
    if (m00 > 0) consider(r0 / m00, 0);
    if (specular) {
      const double det = m00 * m11 - m01 * m01;
      if (det > 1e-12 * std::abs(m00 * m11)) {
        consider((r0 * m11 - r1 * m01) / det, (r1 * m00 - r0 * m01) / det);
      }
      if (m11 > 0) consider(0, r1 / m11);
    }
    out.ambient[c] = best_a;
    out.ks[c] = best_ks;
    out.rss += std::max(0.0, sums.yy[c] - explained + best_f);
  }
  SolveAlbedos(sums, &out);
  return out;
}

// All the sums of one shininess.
Sums AllSums(const Sample& s, Lobe lobe, double shininess, const std::vector<unsigned char>& used) {
  Sums sums = BaseSums(s, used);
  if (lobe != Lobe::kLambert) Add(LobeSums(s, lobe, shininess, used), sums);
  return sums;
}

}  // namespace

Coefficients LinearFit(const Sample& s, Lobe lobe, double shininess,
                       const std::vector<unsigned char>& used) {
  return Solve(AllSums(s, lobe, shininess, used), lobe != Lobe::kLambert, shininess);
}

Coefficients AlbedoFit(const Sample& s, Lobe lobe, const Vec3d& ambient, const Vec3d& ks,
                       double shininess, const std::vector<unsigned char>& used) {
  Coefficients out;
  out.ambient = ambient;
  out.ks = lobe == Lobe::kLambert ? Vec3d::Zero() : ks;
  out.shininess = lobe == Lobe::kLambert ? 0 : shininess;
  SolveAlbedos(AllSums(s, lobe, out.shininess, used), &out);
  return out;
}

Coefficients ProfileFit(const Sample& s, Lobe lobe, const std::vector<unsigned char>& used,
                        double near_shininess) {
  if (lobe == Lobe::kLambert) return LinearFit(s, lobe, 0, used);
  // n = 2^(k/2), 1 … 4096: neighbours differ by √2, finer than the profile cost's basins
  // (a lobe's width changes by 19 % a step). Near a previous answer, its ±2 steps.
  constexpr int kGrid = 25;
  int first = 0, last = kGrid - 1;
  if (near_shininess > 0) {
    const int k0 = static_cast<int>(std::lround(2 * std::log2(near_shininess)));
    first = std::clamp(k0 - 2, 0, kGrid - 1);
    last = std::clamp(k0 + 2, 0, kGrid - 1);
  }
  // The lobe-free sums once; per shininess only the lobe's.
  const Sums base = BaseSums(s, used);
  auto fit = [&](double n) {
    Sums sums = LobeSums(s, lobe, n, used);
    Add(base, sums);
    return Solve(sums, true, n);
  };
  std::vector<double> cost(kGrid, INFINITY);
  for (int k = first; k <= last; ++k) cost[k] = fit(std::exp2(0.5 * k)).rss;
  const int best = static_cast<int>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  // Between the best grid point's neighbours the profile cost is smooth and convex in log n:
  // successive parabolic interpolation, with a golden-section step whenever the parabola's
  // vertex falls outside the bracket or too close to its middle point.
  const double step = 0.5 * std::log(2.0);
  auto profile = [&](double log_n) { return fit(std::exp(log_n)).rss; };
  double a = step * std::max(best - 1, first), b = step * best, c = step * std::min(best + 1, last);
  double fa = a < b ? cost[best - 1] : cost[best], fb = cost[best];
  double fc = c > b ? cost[best + 1] : cost[best];
  for (int it = 0; it < 30 && c - a > 1e-7; ++it) {
    const double p = (b - a) * (fb - fc), q = (b - c) * (fb - fa);
    double u = b - ((b - a) * p - (b - c) * q) / (2 * (p - q));
    const double margin = 1e-3 * (c - a);
    if (!(p != q) || !(u > a + margin && u < c - margin) || std::abs(u - b) < 1e-8) {
      u = (b - a > c - b) ? b - 0.382 * (b - a) : b + 0.382 * (c - b);  // golden step
    }
    const double fu = profile(u);
    if (fu < fb) {
      (u < b ? c : a) = b, (u < b ? fc : fa) = fb;
      b = u, fb = fu;
    } else {
      (u < b ? a : c) = u, (u < b ? fa : fc) = fu;
    }
    if (std::abs(u - b) < 1e-6 && it > 2) break;
  }
  return fit(std::exp(b));
}

Vec3d Predict(const Sample& s, Lobe lobe, const Coefficients& c, std::size_t p, int j) {
  const std::size_t i = p * s.lights + j;
  reflectance::LightFactors<double> f;
  f.diffuse = s.diffuse[i];
  f.specular = lobe == Lobe::kLambert ? 0.0 : LobeFactor(s.cosine(lobe, i), c.shininess);
  const Vec3d& e = s.data->light_intensities[j];
  return c.ambient + reflectance::CombineFactors(f, e, e, c.kd[s.group[p]], c.ks);
}

std::size_t Censor(const Sample& s, Lobe lobe, const Coefficients& c,
                   const std::vector<unsigned char>& allowed, std::vector<unsigned char>* used) {
  std::size_t censored = 0;
  used->assign(allowed.size(), 0);
  for (std::size_t p = 0; p < s.size(); ++p) {
    for (int j = 0; j < s.lights; ++j) {
      const std::size_t i = p * s.lights + j;
      if (!allowed[i]) continue;
      const Vec3d predicted = Predict(s, lobe, c, p, j);
      const float* y = s.y(p, j);
      bool shadowed = false;
      for (int ch = 0; ch < 3; ++ch)
        shadowed = shadowed || y[ch] - predicted[ch] < -s.threshold[p][ch];
      (*used)[i] = !shadowed;
      censored += shadowed;
    }
  }
  return censored;
}

}  // namespace iphong::material::internal
