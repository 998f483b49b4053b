#include "solve/normals.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <numeric>
#include <random>
#include <stdexcept>

#include "core/parallel.h"
#include "core/timing.h"
#include "reflectance/phong.h"
#include "reflectance/shade.h"
#include "solve/few_images.h"
#include "solve/internal.h"

namespace iphong::solve {
namespace {

using Jet2 = ceres::Jet<double, 2>;

enum class PixelStatus { kSolved, kDark, kUnderdetermined };

struct PixelSolution {
  PixelStatus status = PixelStatus::kSolved;
  Vec3d normal = Vec3d(0, 0, 1);
  Vec3d albedo = Vec3d::Zero();
  double specular_scale = 1;  // σ: this pixel's ks is σ times its cluster's
  double residual = -1;
  int iterations = 0;
};

// Woodham on the luminance of (I − ambient)/E over the kept observations.
// (LᵀL)⁻¹Lᵀ for all lights: Woodham without selection is one 3×K product per pixel.
Eigen::Matrix3Xd PseudoInverse(const PhotometricData& data) {
  Eigen::Matrix3Xd l(3, data.images);
  for (int j = 0; j < data.images; ++j) l.col(j) = data.light_directions[j];
  const Eigen::Matrix3d ata = l * l.transpose();
  if (Eigen::LDLT<Eigen::Matrix3d>(ata).rcond() < 1e-9) return Eigen::Matrix3Xd();  // degenerate
  return ata.inverse() * l;
}

// `with_residual`: also the RMS residual of the Lambertian fit (needed only when Woodham's is the
// answer; a start for the Phong fit gets its residual there).
PixelSolution Woodham(const PhotometricData& data, std::size_t p, const NormalOptions& o,
                      const Eigen::Matrix3Xd& pinv, std::vector<std::pair<double, int>>& order,
                      bool with_residual) {
  const int k = data.images;
  const float* obs = data.pixel(p);
  order.clear();
  double brightest = 0;
  for (int j = 0; j < k; ++j) {
    const Vec3d rgb(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]);
    const double g =
        internal::Luminance((rgb - o.ambient_term).cwiseQuotient(data.light_intensities[j]));
    order.emplace_back(g, j);
    brightest = std::max(brightest, g);
  }
  PixelSolution s;
  if (!(brightest > 1e-8)) {
    s.status = PixelStatus::kDark;
    return s;
  }
  int first = static_cast<int>(std::floor(o.discard_dark * k));
  int last = k - static_cast<int>(std::floor(o.discard_bright * k));
  if (last - first < 3) {
    first = 0;
    last = k;
  }
  Vec3d b;
  if (first == 0 && last == k && pinv.cols() == k) {
    b = Vec3d::Zero();
    for (int j = 0; j < k; ++j) b += pinv.col(order[j].second) * order[j].first;
  } else {
    // Only the two cut-offs matter, not the full order: two selections, O(K).
    if (first > 0) std::nth_element(order.begin(), order.begin() + first, order.end());
    if (last < k) std::nth_element(order.begin() + first, order.begin() + last, order.end());
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Vec3d atb = Vec3d::Zero();
    for (int i = first; i < last; ++i) {
      const Vec3d& l = data.light_directions[order[i].second];
      ata += l * l.transpose();
      atb += l * order[i].first;
    }
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
    if (last - first < 3 || ldlt.rcond() < 1e-9) {
      s.status = PixelStatus::kUnderdetermined;
      return s;
    }
    b = ldlt.solve(atb);
  }
  if (!(b.norm() > 1e-12) || !b.allFinite()) {
    s.status = PixelStatus::kDark;
    return s;
  }
  s.normal = b.normalized();
  // Per-channel albedo on the kept, lit observations.
  Vec3d num = Vec3d::Zero(), den = Vec3d::Zero();
  double sq = 0;
  int used = 0;
  for (int i = first; i < last; ++i) {
    const int j = order[i].second;
    const double nl = s.normal.dot(data.light_directions[j]);
    if (nl <= 0) continue;
    const Vec3d rgb = (Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]) - o.ambient_term)
                          .cwiseQuotient(data.light_intensities[j]);
    num += rgb * nl;
    den += Vec3d::Constant(nl * nl);
  }
  s.albedo = num.cwiseQuotient(den.cwiseMax(1e-12)).cwiseMax(0.0);
  if (!with_residual) return s;
  // The residual of the Lambertian model Woodham fits, through the shared model.
  reflectance::Material lambertian;
  lambertian.kd = s.albedo;
  reflectance::ModelOptions lambert;
  lambert.lobe = reflectance::Lobe::kLambert;
  for (int i = first; i < last; ++i) {
    const int j = order[i].second;
    const Vec3d& e = data.light_intensities[j];
    const Vec3d predicted =
        o.ambient_term + reflectance::LightTerm<double>(s.normal, internal::ViewCam(),
                                                        data.light_directions[j], e, e, lambertian,
                                                        lambert);
    sq += (Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]) - predicted).squaredNorm();
    used += 3;
  }
  s.residual = std::sqrt(sq / std::max(used, 1));
  return s;
}

// The per-pixel problem with the albedo eliminated (variable projection): the residuals as a
// function of the normal only. Observations are y = (I_j − Ia⊙ka)/E_j, which under the model
// equal kd·diffuse_j + ks·specular_j per channel (reflectance::ShadingFactors). With `channels`
// = 1 they are reduced to their luminance (exact under the model, since luminance is linear);
// with 3 each channel keeps its own albedo, which is more accurate on real photos whose colours
// depart from the model.
//
// Evaluate() runs the shared model once per light at a point of the tangent-plane chart, as
// ceres::Jets in the two chart coordinates, into the caller's factors. Everything the fit needs
// afterwards comes from those factors without running the model again: the weighted cost with
// its normal equations for any weights (Reduce), the unweighted residuals for the robust weights,
// and the final albedo and residual.
struct PixelModel {
  const PhotometricData* data = nullptr;
  int channels = 3;
  const double* y = nullptr;         // K × channels
  Vec3d ks = Vec3d::Zero();          // per channel (luminance in [0] when channels = 1)
  bool free_specular_scale = false;  // ks scaled per pixel by σ ≥ 0, eliminated like kd
  double specular_prior = 1;         // NormalOptions::specular_prior
  double shininess = 1;
  reflectance::ModelOptions model;
  Vec3d n0, t1, t2;  // chart: N = normalize(n0 + x0 t1 + x1 t2)

  using Factors = std::vector<reflectance::LightFactors<Jet2>>;  // one per light

  // Centres the chart on n (unit).
  void Center(const Vec3d& n) {
    n0 = n;
    const Vec3d a = std::abs(n.x()) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
    t1 = n.cross(a).normalized();
    t2 = n.cross(t1);
  }

  Vec3d Normal(const Eigen::Vector2d& x) const { return (n0 + x[0] * t1 + x[1] * t2).normalized(); }

  void Evaluate(const Eigen::Vector2d& x, Factors* factors) const {
    const Jet2 x0(x[0], 0), x1(x[1], 1);
    const Vec3T<Jet2> raw = n0.cast<Jet2>() + x0 * t1 + x1 * t2;
    const Vec3T<Jet2> normal = raw / raw.norm();
    const Vec3d view = internal::ViewCam();
    const Jet2 n(shininess);
    factors->resize(data->images);
    for (int j = 0; j < data->images; ++j) {
      (*factors)[j] = reflectance::ShadingFactors<Jet2, double>(
          normal, view, data->light_directions[j], n, model);
    }
  }

  // The albedo of each channel and the specular scale σ (1 unless free) eliminated with
  // `weight`, as Jets (their dependence on the normal belongs to the Jacobian of the reduced
  // problem).
  std::array<Jet2, 3> Albedo(const Factors& factors, const double* weight, Jet2* sigma) const {
    *sigma = Jet2(1.0);
    return internal::EliminatedAlbedo<Jet2>(
        factors, channels, [&](int c) { return ks[c]; },
        [&](std::size_t j, int c) { return y[j * channels + c]; },
        [&](std::size_t j) { return weight[j]; }, free_specular_scale ? sigma : nullptr,
        specular_prior);
  }

  // Gauss–Newton normal equations of ½ Σ_j w_j Σ_c r_jc² with r = y − kd·diffuse − ks·specular,
  // accumulated light by light instead of through a K·channels × 2 Jacobian.
  struct NormalEquations {
    double cost = 0;
    Eigen::Matrix2d jtj = Eigen::Matrix2d::Zero();
    Eigen::Vector2d descent = Eigen::Vector2d::Zero();  // −Jᵀr
  };
  NormalEquations Reduce(const Factors& factors, const double* weight) const {
    NormalEquations e;
    const int k = data->images;
    Jet2 sigma;
    const std::array<Jet2, 3> kd = Albedo(factors, weight, &sigma);
    // JᵀJ is symmetric: three sums, filled in at the end.
    double cost = 0, h00 = 0, h01 = 0, h11 = 0, g0 = 0, g1 = 0;
    for (int j = 0; j < k; ++j) {
      const double w = weight[j];
      if (w == 0) continue;
      for (int c = 0; c < channels; ++c) {
        const Jet2 m = kd[c] * factors[j].diffuse + (ks[c] * sigma) * factors[j].specular;
        const double r = y[j * channels + c] - m.a, v0 = w * m.v[0], v1 = w * m.v[1];
        cost += w * r * r;
        h00 += v0 * m.v[0];
        h01 += v0 * m.v[1];
        h11 += v1 * m.v[1];
        g0 += v0 * r;
        g1 += v1 * r;
      }
    }
    e.cost = 0.5 * cost;
    e.jtj << h00, h01, h01, h11;
    e.descent << g0, g1;
    return e;
  }

  // Unweighted residuals at the factors' point, the albedo eliminated with `weight`.
  void Residuals(const Factors& factors, const double* weight, double* out) const {
    Jet2 sigma;
    const std::array<Jet2, 3> kd = Albedo(factors, weight, &sigma);
    for (int c = 0; c < channels; ++c) {
      for (int j = 0; j < data->images; ++j) {
        out[j * channels + c] = y[j * channels + c] - kd[c].a * factors[j].diffuse.a -
                                sigma.a * ks[c] * factors[j].specular.a;
      }
    }
  }
};

// Per-thread solver state: allocated once per chunk of pixels, never per pixel.
struct PixelFitter {
  const PhotometricData& data;
  const NormalOptions& options;
  const Vec3d ks;
  PixelModel model;
  PixelModel::Factors factors, trial;  // at the current point and the trial step (swapped)
  std::vector<reflectance::LightFactors<double>> values;  // the factors' values, for the output
  std::vector<double> y_rgb, y_lum, usable, weights, residuals;
  std::vector<std::pair<double, int>> order;
  double scale = 1;      // the Cauchy scale of the pixel being fitted (not the specular σ)
  NormalOptions darker;  // Woodham on the darker observations: the second start

  PixelFitter(const PhotometricData& d, const NormalOptions& o, const Vec3d& fit_ks,
              double shininess)
      : data(d), options(o), ks(fit_ks) {
    model.data = &d;
    model.channels = o.color_residuals ? 3 : 1;
    model.ks = o.color_residuals ? ks : Vec3d(internal::Luminance(ks), 0, 0);
    model.shininess = shininess;
    // No specular coefficient means no specular term: the Lambertian model, not a zero lobe.
    model.model.lobe = ks.isZero() ? reflectance::Lobe::kLambert : o.model;
    model.free_specular_scale = o.varying_specular && !o.material_known && !ks.isZero();
    model.specular_prior = o.specular_prior;
    factors.reserve(d.images);
    trial.reserve(d.images);
    y_rgb.resize(3 * d.images);
    y_lum.resize(d.images);
    usable.resize(d.images);
    order.reserve(d.images);
    darker = o;
    darker.discard_dark = 0.2;
    darker.discard_bright = 0.4;
    weights.resize(d.images);
    residuals.resize(3 * d.images);
  }

  // Refines `s` (from Woodham); where the fit leaves more than `restart_residual` of the pixel's
  // brightness unexplained, it also starts from Woodham on the darker observations (highlights
  // bias the first start toward a local minimum) and keeps the better of the two.
  void FitWithRestart(std::size_t p, PixelSolution& s) {
    Fit(p, s);
    if (std::isinf(options.restart_residual)) return;  // off (the default)
    if (!(s.residual > options.restart_residual * MeanObservation(p))) return;
    PixelSolution second = Woodham(data, p, darker, Eigen::Matrix3Xd(), order, false);
    if (second.status != PixelStatus::kSolved) return;
    // A start already near the solution (within 2 degrees) would converge to the same place.
    if (second.normal.dot(s.normal) > std::cos(2.0 * M_PI / 180)) return;
    const double first_cost = RobustCost();  // before the second fit replaces the factors
    second.iterations = 0;
    Fit(p, second);
    s.iterations += second.iterations;
    if (RobustCost() < first_cost) {
      second.iterations = s.iterations;
      s = second;
    }
  }

  double MeanObservation(std::size_t p) const {
    const float* obs = data.pixel(p);
    double sum = 0;
    for (int i = 0; i < 3 * data.images; ++i) sum += obs[i];
    return std::max(sum / (3 * data.images), 1e-9);
  }

  // Levenberg–Marquardt on the two chart coordinates with fixed weights, from x (updated in
  // place; `factors` are the model's at x on entry and on return). The damping follows
  // ceres::TinySolver; unlike it, every trial point is evaluated with its derivatives, so an
  // accepted step costs one run of the model, not two.
  int Minimize(Eigen::Vector2d& x) {
    // A relative cost change below this leaves the normal within ~1e-3 σ/kd of the optimum, far
    // inside the noise (on DiLiGenT cat 1e-12 spends twice the iterations for the same figures).
    const double kCostTolerance = 1e-6;
    PixelModel::NormalEquations eq = model.Reduce(factors, weights.data());
    double u = 1e-4, v = 2;
    int iterations = 0;
    for (; iterations < options.max_iterations; ++iterations) {
      Eigen::Matrix2d damped = eq.jtj;
      for (int i = 0; i < 2; ++i) damped(i, i) += u * std::clamp(eq.jtj(i, i), 1e-6, 1e32);
      const Eigen::Vector2d step = damped.ldlt().solve(eq.descent);
      // 1e-8 of the chart is ~1e-6 degrees: far below any useful precision, and stopping there
      // saves the iterations that only polish noise.
      if (!step.allFinite() || step.norm() < 1e-8) break;
      const Eigen::Vector2d x_new = x + step;
      model.Evaluate(x_new, &trial);
      const PixelModel::NormalEquations eq_new = model.Reduce(trial, weights.data());
      const double change = eq.cost - eq_new.cost;
      const double predicted = step.dot(eq.descent - 0.5 * eq.jtj * step);
      const double rho = change / predicted;
      if (rho > 0) {
        x = x_new;
        std::swap(factors, trial);
        eq = eq_new;
        if (std::abs(change) < kCostTolerance * eq.cost) break;
        const double t = 2 * rho - 1;
        u *= std::max(1.0 / 3, 1 - t * t * t);
        v = 2;
      } else {
        if (std::abs(change) < kCostTolerance * eq.cost) break;
        u *= v;
        v *= 2;
      }
    }
    return iterations;
  }

  // Refines `s` (from Woodham) in place. Buffers are the fitter's: nothing is allocated here.
  void Fit(std::size_t p, PixelSolution& s) {
    const int k = data.images;
    const float* obs = data.pixel(p);
    double mean = 0;
    int count = 0;
    for (int j = 0; j < k; ++j) {
      const Vec3d rgb(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]);
      const bool saturated = rgb.maxCoeff() >= options.saturation;
      usable[j] = saturated ? 0.0 : 1.0;
      const Vec3d y = (rgb - options.ambient_term).cwiseQuotient(data.light_intensities[j]);
      for (int c = 0; c < 3; ++c) y_rgb[3 * j + c] = y[c];
      y_lum[j] = internal::Luminance(y);
      if (!saturated) {
        mean += std::abs(y_lum[j]);
        ++count;
      }
    }
    if (count < 3) {  // too few unsaturated observations to fit: Woodham's answer stays
      const int iterations = s.iterations;
      s = Woodham(data, p, options, Eigen::Matrix3Xd(), order, true);
      s.iterations = iterations;
      return;
    }
    scale = options.robust_scale * std::max(mean / count, 1e-6);
    model.y = model.channels == 1 ? y_lum.data() : y_rgb.data();
    weights = usable;
    model.Center(s.normal);
    Eigen::Vector2d x = Eigen::Vector2d::Zero();
    model.Evaluate(x, &factors);
    const int ch = model.channels;
    Vec3d normal = s.normal;
    for (int round = 0; round < options.irls_rounds; ++round) {
      s.iterations += Minimize(x);
      const Vec3d previous = normal;
      normal = model.Normal(x);
      // Reweighting can no longer move a normal that moved less than 0.01 degrees.
      if (round > 0 && previous.dot(normal) > std::cos(1e-2 * M_PI / 180)) break;
      // Cauchy weights from the unweighted residuals of the usable observations, at the new
      // normal: one weight per image, since a cast shadow or highlight affects every channel.
      model.Residuals(factors, usable.data(), residuals.data());
      for (int j = 0; j < k; ++j) {
        double r2 = 0;
        for (int c = 0; c < ch; ++c) r2 += std::pow(residuals[j * ch + c] / scale, 2);
        weights[j] = usable[j] / (1.0 + r2 / ch);
      }
      // A chart far from its centre bends; re-centre it (the factors' derivatives change).
      if (x.norm() > 0.25 && round + 1 < options.irls_rounds) {
        model.Center(normal);
        x.setZero();
        model.Evaluate(x, &factors);
      }
    }
    s.normal = normal;
    AlbedoAndResidual(obs, s);
  }

  // Σ log(1 + (r/σ)²) over the usable observations at the last fit's normal, with that pixel's
  // σ: what chooses between two starts.
  double RobustCost() {
    model.Residuals(factors, usable.data(), residuals.data());
    double cost = 0;
    for (int i = 0; i < data.images * model.channels; ++i) {
      cost += std::log1p(std::pow(residuals[i] / scale, 2));
    }
    return cost;
  }

  // The RGB albedo, eliminated as in the fit with its final weights, and the RMS difference
  // between the observations and the shared model over the usable ones (its factors at the final
  // normal, combined by reflectance::CombineFactors, plus Ia⊙ka).
  void AlbedoAndResidual(const float* obs, PixelSolution& s) {
    const int k = data.images;
    std::vector<reflectance::LightFactors<double>>& f = values;
    f.resize(k);
    for (int j = 0; j < k; ++j) f[j] = {factors[j].diffuse.a, factors[j].specular.a};
    double sigma = 1;
    const std::array<double, 3> kd = internal::EliminatedAlbedo<double>(
        f, 3, [&](int c) { return ks[c]; }, [&](std::size_t j, int c) { return y_rgb[3 * j + c]; },
        [&](std::size_t j) { return weights[j]; }, model.free_specular_scale ? &sigma : nullptr,
        options.specular_prior);
    s.albedo = Vec3d(kd[0], kd[1], kd[2]);
    s.specular_scale = sigma;
    double sq = 0;
    int used = 0;
    for (int j = 0; j < k; ++j) {
      if (usable[j] == 0) continue;
      const Vec3d& e = data.light_intensities[j];
      const Vec3d predicted = options.ambient_term +
                              reflectance::CombineFactors<double>(f[j], e, e, s.albedo, sigma * ks);
      sq += (Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]) - predicted).squaredNorm();
      used += 3;
    }
    s.residual = std::sqrt(sq / std::max(used, 1));
  }
};

// Global fit of ks (RGB), log-shininess and the ambient term Ia⊙ka (RGB) over sampled pixels,
// normals fixed, albedo eliminated as in the per-pixel fit.
struct SpecularCost {
  using Jet7 = ceres::Jet<double, 7>;  // ks (3) + log-shininess (1) + ambient (3)
  const PhotometricData* data;
  std::size_t p;
  Vec3d normal;
  reflectance::ModelOptions model;
  std::vector<double> weight;                                        // K, 0 for saturated images
  mutable std::vector<reflectance::LightFactors<double>> factors_d;  // reused between calls
  mutable std::vector<reflectance::LightFactors<Jet7>> factors_j;

  template <typename T>
  bool operator()(const T* ks, const T* log_n, const T* ambient, T* residuals) const {
    std::vector<reflectance::LightFactors<T>>* f;
    if constexpr (std::is_same_v<T, double>) {
      f = &factors_d;
    } else {
      f = &factors_j;
    }
    const int k = data->images;
    f->resize(k);
    const T shininess = exp(log_n[0]);
    // With the normal fixed the factors depend on the parameters only through the shininess: the
    // model runs on one-derivative Jets in n, and the chain rule carries d/dn to the parameters
    // (7 derivatives per operation would be spent on zeros).
    using Jet1 = ceres::Jet<double, 1>;
    double n_value;
    if constexpr (std::is_same_v<T, double>) {
      n_value = shininess;
    } else {
      n_value = shininess.a;
    }
    const auto chain = [&](const Jet1& x) {
      if constexpr (std::is_same_v<T, double>) {
        return x.a;
      } else {
        T out(x.a);
        out.v = x.v[0] * shininess.v;
        return out;
      }
    };
    const Vec3T<Jet1> n = normal.cast<Jet1>();
    for (int j = 0; j < k; ++j) {
      const reflectance::LightFactors<Jet1> f1 = reflectance::ShadingFactors<Jet1, double>(
          n, internal::ViewCam(), data->light_directions[j], Jet1(n_value, 0), model);
      (*f)[j] = {chain(f1.diffuse), chain(f1.specular)};
    }
    const float* obs = data->pixel(p);
    const auto y = [&](std::size_t j, int c) {
      const double inverse_e = 1.0 / data->light_intensities[j][c];
      return (static_cast<double>(obs[3 * j + c]) - ambient[c]) * inverse_e;
    };
    const std::array<T, 3> kd = internal::EliminatedAlbedo<T>(
        *f, 3, [&](int c) { return ks[c]; }, y, [&](std::size_t j) { return weight[j]; });
    for (int c = 0; c < 3; ++c) {
      for (int j = 0; j < k; ++j) {
        residuals[3 * j + c] = T(std::sqrt(weight[j])) *
                               (y(j, c) - kd[c] * (*f)[j].diffuse - ks[c] * (*f)[j].specular);
      }
    }
    return true;
  }
};

struct SpecularFit {
  Vec3d ks = Vec3d::Zero();
  double shininess = 1;
  Vec3d ambient = Vec3d::Zero();
  double cost = 0, cost_without_specular = 0;
};

// The range of the estimated shininess. At the lower end the lobe is as broad as the diffuse
// term (EstimateSpecular treats that as not identifiable).
constexpr double kMinShininess = 1.0, kMaxShininess = 1000.0;

SpecularFit FitSpecular(const PhotometricData& data, const std::vector<std::size_t>& sample,
                        const std::vector<PixelSolution>& solutions, const NormalOptions& o,
                        const SpecularFit& start) {
  double ks[3] = {start.ks[0], start.ks[1], start.ks[2]};
  double log_n = std::log(start.shininess);
  double ambient[3] = {start.ambient[0], start.ambient[1], start.ambient[2]};
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::vector<SpecularCost*> costs;
  for (std::size_t p : sample) {
    if (solutions[p].status != PixelStatus::kSolved) continue;
    auto* cost = new SpecularCost{&data, p, solutions[p].normal, {}, {}, {}, {}};
    cost->model.lobe = o.model;
    cost->weight.resize(data.images);
    const float* obs = data.pixel(p);
    double mean = 0;  // of y = I / E, the scale of the residuals
    for (int j = 0; j < data.images; ++j) {
      const Vec3d rgb(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]);
      cost->weight[j] = rgb.maxCoeff() >= o.saturation ? 0.0 : 1.0;
      mean += internal::Luminance(rgb.cwiseQuotient(data.light_intensities[j])) / data.images;
    }
    costs.push_back(cost);
    auto* function = new ceres::AutoDiffCostFunction<SpecularCost, ceres::DYNAMIC, 3, 1, 3>(
        cost, 3 * data.images, ceres::DO_NOT_TAKE_OWNERSHIP);
    problem.AddResidualBlock(function, new ceres::CauchyLoss(o.robust_scale * std::max(mean, 1e-6)),
                             ks, &log_n, ambient);
  }
  SpecularFit fit;
  if (costs.empty()) return fit;
  for (int c = 0; c < 3; ++c) {
    problem.SetParameterLowerBound(ks, c, 0.0);
    problem.SetParameterLowerBound(ambient, c, 0.0);
  }
  problem.SetParameterLowerBound(&log_n, 0, std::log(kMinShininess));
  problem.SetParameterUpperBound(&log_n, 0, std::log(kMaxShininess));
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = 50;
  solver_options.num_threads = ResolveThreads(o.threads);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  fit.ks = Vec3d(ks[0], ks[1], ks[2]);
  fit.shininess = std::exp(log_n);
  fit.ambient = Vec3d(ambient[0], ambient[1], ambient[2]);
  fit.cost = summary.final_cost;
  // The same robust cost with no specular term (the parameter blocks are this memory), for the
  // identifiability test.
  std::fill(ks, ks + 3, 0.0);
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &fit.cost_without_specular, nullptr, nullptr,
                   nullptr);
  for (SpecularCost* cost : costs) delete cost;
  return fit;
}

// ks (RGB), shininess and ambient of one group of pixels (a cluster, or the whole object):
// rounds of the global fit over a sample alternate with per-pixel refits of the sample.
void EstimateSpecular(const PhotometricData& data, const std::vector<std::size_t>& members,
                      const NormalOptions& options, std::vector<PixelSolution>& solutions,
                      SpecularCluster* cluster) {
  std::vector<std::size_t> sample = members;
  std::mt19937 rng(12345);
  std::shuffle(sample.begin(), sample.end(), rng);
  sample.resize(std::min<std::size_t>(sample.size(), options.specular_sample));
  SpecularFit fit;
  // One moderate start; the bounded log-shininess has taken it to n = 6 … 130 on DiLiGenT and
  // back to the true value on renders.
  fit.ks = Vec3d::Constant(0.1);
  fit.shininess = 20;
  for (int round = 0; round < options.specular_rounds; ++round) {
    fit = FitSpecular(data, sample, solutions, options, fit);
    NormalOptions with_ambient = options;
    with_ambient.ambient_term = fit.ambient;
    // Only the sample's normals feed the next global fit; the rest are fitted once at the end.
    ParallelFor(0, sample.size(), 64, options.threads, [&](std::size_t b, std::size_t e) {
      PixelFitter fitter(data, with_ambient, fit.ks, fit.shininess);
      for (std::size_t i = b; i < e; ++i) {
        PixelSolution refined = solutions[sample[i]];
        fitter.FitWithRestart(sample[i], refined);
        solutions[sample[i]].normal = refined.normal;
      }
    });
  }
  const double gain = fit.cost_without_specular > 0 ? 1 - fit.cost / fit.cost_without_specular : 0;
  if (!(fit.ks.maxCoeff() > 1e-3) || gain < 0.02) {
    cluster->identifiable = false;
    cluster->note =
        "no highlights seen: ks and shininess are not identifiable; fitted without a specular "
        "term";
    return;
  }
  // At its lower bound the lobe trades places with the diffuse term (seen on grazing-angle
  // clusters): not a highlight either.
  if (fit.shininess < 1.05 * kMinShininess) {
    cluster->identifiable = false;
    cluster->note =
        "the specular lobe fitted as broad as the diffuse term (shininess 1): not identifiable";
    return;
  }
  cluster->ks = fit.ks;
  cluster->shininess = fit.shininess;
  cluster->ambient_term = fit.ambient;
  cluster->estimated = true;
  cluster->note =
      "estimated from " + std::to_string(sample.size()) + " pixels; robust cost reduced by " +
      std::to_string(static_cast<int>(std::round(100 * gain))) + "% against no specular term";
}

// k-means (k-means++ seeds, fixed random stream) of the solved pixels' albedo on chromaticity
// (r, g over r + g + b) and a tenth of the log brightness; colour tells materials apart, shading
// leftovers in the brightness should not. Returns the number of non-empty clusters, numbered
// from the largest.
int ClusterAlbedo(const std::vector<PixelSolution>& solutions, int k,
                  std::vector<int>* cluster_of) {
  std::vector<std::size_t> solved;
  std::vector<Eigen::Vector3d> feature;
  for (std::size_t p = 0; p < solutions.size(); ++p) {
    const Vec3d a = solutions[p].albedo.cwiseMax(0.0);
    const double sum = a.sum();
    if (solutions[p].status != PixelStatus::kSolved || !(sum > 0)) continue;
    solved.push_back(p);
    feature.emplace_back(a[0] / sum, a[1] / sum, 0.1 * std::log(sum));
  }
  std::fill(cluster_of->begin(), cluster_of->end(), 0);
  if (static_cast<int>(solved.size()) < 2 * k) return 1;
  std::mt19937 rng(7);
  std::vector<Eigen::Vector3d> centers = {feature[rng() % feature.size()]};
  std::vector<double> d2(feature.size());
  while (static_cast<int>(centers.size()) < k) {
    for (std::size_t i = 0; i < feature.size(); ++i) {
      d2[i] = INFINITY;
      for (const auto& c : centers) d2[i] = std::min(d2[i], (feature[i] - c).squaredNorm());
    }
    std::discrete_distribution<std::size_t> pick(d2.begin(), d2.end());
    centers.push_back(feature[pick(rng)]);
  }
  std::vector<int> label(feature.size(), 0);
  for (int iteration = 0; iteration < 30; ++iteration) {
    bool changed = false;
    for (std::size_t i = 0; i < feature.size(); ++i) {
      int best = 0;
      for (int c = 1; c < k; ++c) {
        if ((feature[i] - centers[c]).squaredNorm() < (feature[i] - centers[best]).squaredNorm())
          best = c;
      }
      changed |= best != label[i];
      label[i] = best;
    }
    std::vector<Eigen::Vector3d> sum(k, Eigen::Vector3d::Zero());
    std::vector<int> count(k, 0);
    for (std::size_t i = 0; i < feature.size(); ++i) sum[label[i]] += feature[i], ++count[label[i]];
    for (int c = 0; c < k; ++c) {
      if (count[c] > 0) centers[c] = sum[c] / count[c];
    }
    if (!changed && iteration > 0) break;
  }
  // Renumber from the largest cluster, dropping empty ones.
  std::vector<int> count(k, 0);
  for (int l : label) ++count[l];
  std::vector<int> order(k);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return count[a] > count[b]; });
  std::vector<int> rename(k, 0);
  int used = 0;
  for (int c : order) {
    if (count[c] > 0) rename[c] = used++;
  }
  for (std::size_t i = 0; i < solved.size(); ++i) (*cluster_of)[solved[i]] = rename[label[i]];
  return used;
}

}  // namespace

std::string NormalOptions::Validate() const {
  if (!(discard_dark >= 0 && discard_bright >= 0 && discard_dark + discard_bright < 1)) {
    return "discard fractions must be >= 0 and sum to less than 1";
  }
  if (!(saturation > 0)) return "saturation level must be > 0";
  if (!(robust_scale > 0)) return "robust scale must be > 0";
  if (irls_rounds < 1 || max_iterations < 1) return "irls rounds and iterations must be >= 1";
  if (!ambient_term.allFinite() || (ambient_term.array() < 0).any()) {
    return "ambient term must be finite and >= 0";
  }
  if (!ks.allFinite() || (ks.array() < 0).any() || !std::isfinite(shininess) || shininess < 0) {
    return "ks and shininess must be finite and >= 0";
  }
  if (specular_rounds < 0 || specular_sample < 1) return "specular rounds/sample out of range";
  if (specular_clusters < 1 || specular_clusters > 16) return "specular clusters must be in 1..16";
  if (!(specular_prior > 0) || !std::isfinite(specular_prior)) return "specular prior must be > 0";
  return "";
}

NormalResult EstimateNormals(const PhotometricData& data, const NormalOptions& options) {
  if (auto m = data.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (data.images < 3) {
    throw std::invalid_argument("per-pixel photometric stereo needs at least 3 images, got " +
                                std::to_string(data.images));
  }
  const std::size_t pixels = data.pixel_count();
  std::vector<PixelSolution> solutions(pixels);
  NormalResult result;
  result.model = options.model;
  result.summary.pixels = pixels;

  const bool nonlinear = options.model != reflectance::Lobe::kLambert;
  auto start = Clock::now();
  const Eigen::Matrix3Xd pinv = PseudoInverse(data);
  ParallelFor(0, pixels, 1024, options.threads, [&](std::size_t b, std::size_t e) {
    std::vector<std::pair<double, int>> order;
    order.reserve(data.images);
    for (std::size_t p = b; p < e; ++p)
      solutions[p] = Woodham(data, p, options, pinv, order, !nonlinear);
  });
  result.summary.init_seconds = SecondsSince(start);

  // Clusters of the albedo (one: the whole object) and their specular coefficients.
  std::vector<int> cluster_of(pixels, 0);
  int clusters = 1;
  if (nonlinear && !options.material_known && options.specular_clusters > 1) {
    clusters = ClusterAlbedo(solutions, options.specular_clusters, &cluster_of);
  }
  start = Clock::now();
  for (int c = 0; c < clusters; ++c) {
    std::vector<std::size_t> members;
    for (std::size_t p = 0; p < pixels; ++p)
      if (cluster_of[p] == c && solutions[p].status == PixelStatus::kSolved) members.push_back(p);
    SpecularCluster cluster;
    cluster.pixels = members.size();
    for (std::size_t p : members) cluster.albedo_center += solutions[p].albedo;
    if (!members.empty()) cluster.albedo_center /= static_cast<double>(members.size());
    if (!nonlinear) {
      // Lambertian: no specular term to speak of.
    } else if (options.material_known) {
      cluster.ks = options.ks;
      cluster.shininess = options.shininess;
      cluster.ambient_term = options.ambient_term;
    } else {
      EstimateSpecular(data, members, options, solutions, &cluster);
    }
    result.clusters.push_back(cluster);
  }
  if (nonlinear && !options.material_known) result.summary.specular_seconds = SecondsSince(start);
  // A cluster that saw no highlight borrows from the largest one that did (clusters are numbered
  // from the largest): a matte-looking part of a shiny object is more likely than a second
  // material.
  const auto donor = std::find_if(result.clusters.begin(), result.clusters.end(),
                                  [](const SpecularCluster& c) { return c.estimated; });
  if (donor != result.clusters.end()) {
    for (SpecularCluster& c : result.clusters) {
      if (c.estimated || c.identifiable) continue;
      c.ks = donor->ks;
      c.shininess = donor->shininess;
      c.ambient_term = donor->ambient_term;
      c.note = "no highlights seen in this cluster: coefficients of cluster #" +
               std::to_string(donor - result.clusters.begin());
    }
  }
  const auto largest = std::max_element(
      result.clusters.begin(), result.clusters.end(),
      [](const SpecularCluster& a, const SpecularCluster& b) { return a.pixels < b.pixels; });
  result.ks = largest->ks;
  result.shininess = largest->shininess;
  result.ambient_term = largest->ambient_term;
  result.specular_identifiable = largest->identifiable;
  result.specular_note = largest->note;
  result.material_estimated = std::any_of(result.clusters.begin(), result.clusters.end(),
                                          [](const SpecularCluster& c) { return c.estimated; });

  if (nonlinear) {
    start = Clock::now();
    // The options of each cluster (its ambient term), for its fitters.
    std::vector<NormalOptions> cluster_options(clusters, options);
    for (int c = 0; c < clusters; ++c)
      cluster_options[c].ambient_term = result.clusters[c].ambient_term;
    std::atomic<std::size_t> done{0};
    std::atomic<long long> iterations{0};
    ParallelFor(0, pixels, 256, options.threads, [&](std::size_t b, std::size_t e) {
      std::vector<std::unique_ptr<PixelFitter>> fitters(clusters);  // made when first needed
      long long local = 0;
      for (std::size_t p = b; p < e; ++p) {
        if (solutions[p].status != PixelStatus::kSolved) continue;
        const int c = cluster_of[p];
        if (!fitters[c]) {
          const SpecularCluster& k = result.clusters[c];
          fitters[c] = std::make_unique<PixelFitter>(data, cluster_options[c], k.ks, k.shininess);
        }
        fitters[c]->FitWithRestart(p, solutions[p]);
        local += solutions[p].iterations;
      }
      iterations += local;
      const std::size_t now = done += e - b;
      if (options.progress) options.progress(static_cast<double>(now) / pixels);
    });
    result.summary.iterations = iterations.load();
    result.summary.solve_seconds = SecondsSince(start);
  }
  if (clusters > 1) {
    result.cluster_map = ImageF(data.width, data.height, 1, -1.0f);
    for (std::size_t i = 0; i < pixels; ++i) {
      result.cluster_map.pixels[static_cast<std::size_t>(data.pixels[i])] =
          static_cast<float>(cluster_of[i]);
    }
  }

  result.normals = ImageF(data.width, data.height, 3);
  result.albedo = ImageF(data.width, data.height, 3);
  result.residual = ImageF(data.width, data.height, 1);
  if (nonlinear) result.specular = ImageF(data.width, data.height, 3);
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::size_t p = static_cast<std::size_t>(data.pixels[i]);
    const PixelSolution& s = solutions[i];
    if (s.status == PixelStatus::kDark) ++result.summary.dark_pixels;
    if (s.status == PixelStatus::kUnderdetermined) ++result.summary.underdetermined_pixels;
    const bool ok = s.status == PixelStatus::kSolved && s.normal.allFinite();
    const Vec3d n = ok ? s.normal : Vec3d(0, 0, 1);  // never NaN: flagged in the residual map
    for (int c = 0; c < 3; ++c) {
      result.normals.pixels[3 * p + c] = static_cast<float>(n[c]);
      result.albedo.pixels[3 * p + c] = ok ? static_cast<float>(s.albedo[c]) : 0.0f;
      if (nonlinear && ok) {
        result.specular.pixels[3 * p + c] =
            static_cast<float>(s.specular_scale * result.clusters[cluster_of[i]].ks[c]);
      }
    }
    result.residual.pixels[p] = ok ? static_cast<float>(s.residual) : -1.0f;
  }
  result.summary.success = true;
  result.summary.message =
      "solved " +
      std::to_string(pixels - result.summary.dark_pixels - result.summary.underdetermined_pixels) +
      " of " + std::to_string(pixels) + " pixels";
  return result;
}

NormalResult RecoverNormals(const PhotometricData& data, const NormalOptions& options) {
  if (data.images >= 3) return EstimateNormals(data, options);
  if (!options.material_known || !options.known_albedo) {
    throw std::invalid_argument("with " + std::to_string(data.images) +
                                " image(s) the coefficients must be known, kd (a uniform albedo) "
                                "included");
  }
  FewImageOptions few;
  few.model = options.model;
  few.material.kd = *options.known_albedo;
  few.material.ks = options.ks;
  few.material.shininess = options.shininess;
  few.ambient_term = options.ambient_term;
  few.threads = options.threads;
  const FewImageResult r = EstimateNormalsFewImages(data, few);
  NormalResult result;
  result.model = options.model;
  result.normals = r.normals;
  result.residual = r.residual;
  result.ambiguity_deg = r.ambiguity_deg;
  result.ks = options.ks;
  result.shininess = options.shininess;
  result.ambient_term = options.ambient_term;
  result.albedo = ImageF(data.width, data.height, 3);
  for (int p : data.pixels) {
    for (int c = 0; c < 3; ++c)
      result.albedo.pixels[3 * p + c] = static_cast<float>(few.material.kd[c]);
  }
  result.summary.success = true;
  result.summary.pixels = data.pixel_count();
  result.summary.solve_seconds = r.solve_seconds;
  result.summary.iterations = r.iterations;
  result.summary.message = r.message;
  return result;
}

}  // namespace iphong::solve
