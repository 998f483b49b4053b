#include "solve/pixel_fit.h"

#include <ceres/jet.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace iphong::solve {
// Not an anonymous namespace: PixelFitter::State (declared in the header, so of external linkage)
// holds a PixelModel.
namespace pixel_fit_internal {

using Jet2 = ceres::Jet<double, 2>;
using Factors = std::vector<reflectance::LightFactors<Jet2>>;  // one per light

// The per-pixel problem with the linear coefficients eliminated: the residuals as a function of
// the normal only. With `channels` = 1 the observations are reduced to their luminance (exact
// under the model, since luminance is linear); with 3 each channel keeps its own coefficients,
// which is more accurate on real photos whose colours depart from the model.
//
// Evaluate() runs the shared model once per light at a point of the chart, as Jets in the two
// chart coordinates. Everything the fit needs afterwards comes from those factors: the weighted
// cost with its normal equations (Reduce), the unweighted residuals for the censoring, and the
// final coefficients and residual.
struct PixelModel {
  const PhotometricData* data = nullptr;
  int channels = 3;
  const double* y = nullptr;      // K × channels
  std::optional<Vec3d> known_ks;  // per channel (luminance in [0] when channels = 1)
  std::optional<Vec3d> ks_prior;  // the same layout
  double ks_prior_weight = 0;
  double ks_ridge = internal::kKsRidge;
  double shininess = 1;
  reflectance::ModelOptions model;
  const PixelLights* lights = nullptr;  // the pixel's L_j and V
  Vec3d n0, t1, t2;                     // chart: N = normalize(n0 + x0 t1 + x1 t2)
  // The object's misfit by N·L (ShadingWeights::offset) taken off the observations, in each
  // channel's share of the pixel's brightness; null: none.
  const ShadingWeights* offset = nullptr;
  double offset_scale[3] = {0, 0, 0};

  mutable std::vector<double> adjusted;  // the observations less their offsets (Observations)
  mutable reflectance::LobeScratch<Jet2> scratch;  // Evaluate's

  // The observations (K × channels) the fit at these factors sees: y less each light's offset at
  // the factors' N·L (a light behind the surface has none: the model predicts it dark); y itself
  // without offsets. The band is looked up once per light, not per channel and use.
  const double* Observations(const Factors& f) const {
    if (!offset) return y;
    adjusted.resize(f.size() * channels);
    for (std::size_t j = 0; j < f.size(); ++j) {
      const double o = f[j].diffuse.a > 0 ? offset->OffsetAt(f[j].diffuse.a) : 0.0;
      for (int c = 0; c < channels; ++c)
        adjusted[j * channels + c] = y[j * channels + c] - o * offset_scale[c];
    }
    return adjusted.data();
  }

  void Center(const Vec3d& n) {
    n0 = n;
    const Vec3d a = std::abs(n.x()) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
    t1 = n.cross(a).normalized();
    t2 = n.cross(t1);
  }

  Vec3d Normal(const Eigen::Vector2d& x) const { return (n0 + x[0] * t1 + x[1] * t2).normalized(); }

  // With `weight`, only the lights whose weight is nonzero (`weighted`) or zero (!weighted): a
  // light of weight 0 takes no part in a step (Reduce, Coefficients), so a trial point need not
  // run the model there; the rest are filled in once the steps end.
  void Evaluate(const Eigen::Vector2d& x, Factors* factors, const double* weight = nullptr,
                bool weighted = true) const {
    const Jet2 x0(x[0], 0), x1(x[1], 1);
    const Vec3T<Jet2> raw = n0.cast<Jet2>() + x0 * t1 + x1 * t2;
    const Vec3T<Jet2> normal = raw / raw.norm();
    factors->resize(data->images);
    reflectance::ShadingFactorsOfLights<Jet2, double>(
        normal, lights->view(), &lights->direction(0), data->images, shininess, model,
        [&](int j) { return !weight || (weight[j] != 0) == weighted; }, scratch, factors->data());
  }

  // `obs`: Observations(factors).
  std::array<internal::CoefficientPair<Jet2>, 3> Coefficients(const Factors& factors,
                                                              const double* weight,
                                                              const double* obs) const {
    return internal::EliminatedCoefficients<Jet2>(
        factors, channels, known_ks ? known_ks->data() : nullptr,
        [&](std::size_t j, int c) { return obs[j * channels + c]; },
        [&](std::size_t j) { return weight[j]; }, ks_prior ? ks_prior->data() : nullptr,
        ks_prior_weight, ks_ridge);
  }

  // Gauss–Newton normal equations of ½ Σ_j w_j Σ_c r_jc² with r = y − kd·d − ks·s, accumulated
  // light by light instead of through a K·channels × 2 Jacobian.
  struct NormalEquations {
    double cost = 0;
    Eigen::Matrix2d jtj = Eigen::Matrix2d::Zero();
    Eigen::Vector2d descent = Eigen::Vector2d::Zero();  // −Jᵀr
  };
  NormalEquations Reduce(const Factors& factors, const double* weight) const {
    NormalEquations e;
    const double* obs = Observations(factors);
    const auto k = Coefficients(factors, weight, obs);
    double cost = 0, h00 = 0, h01 = 0, h11 = 0, g0 = 0, g1 = 0;
    for (int j = 0; j < data->images; ++j) {
      const double w = weight[j];
      if (w == 0) continue;
      for (int c = 0; c < channels; ++c) {
        const Jet2 m = k[c].kd * factors[j].diffuse + k[c].ks * factors[j].specular;
        const double r = obs[j * channels + c] - m.a, v0 = w * m.v[0], v1 = w * m.v[1];
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

  // Unweighted residuals at the factors' point, the coefficients eliminated with `weight`.
  void Residuals(const Factors& factors, const double* weight, double* out) const {
    const double* obs = Observations(factors);
    const auto k = Coefficients(factors, weight, obs);
    for (int j = 0; j < data->images; ++j) {
      for (int c = 0; c < channels; ++c) {
        out[j * channels + c] = obs[j * channels + c] - k[c].kd.a * factors[j].diffuse.a -
                                k[c].ks.a * factors[j].specular.a;
      }
    }
  }
};

}  // namespace pixel_fit_internal
using namespace pixel_fit_internal;

std::string ShadingWeights::Validate() const {
  if (upper.size() != weight.size()) return "shading weights: as many band edges as weights needed";
  if (!offset.empty() && offset.size() != weight.size()) {
    return "shading weights: as many offsets as weights needed";
  }
  for (const double v : offset) {
    if (!(std::abs(v) <= 1)) return "shading weights: each offset finite and within [-1, 1]";
  }
  for (std::size_t b = 0; b < weight.size(); ++b) {
    if (!(weight[b] > 0 && weight[b] <= 1)) return "shading weights: each weight in (0, 1]";
    if (b > 0 && !(upper[b] >= upper[b - 1])) return "shading weights: band edges must ascend";
  }
  return "";
}

struct PixelFitter::State {
  const PhotometricData& data;
  PixelFitSettings settings;
  PixelLights lights;
  PixelModel model;
  Factors factors, trial;  // at the current point and the trial step (swapped)
  std::vector<reflectance::LightFactors<double>> values;
  std::vector<double> y_rgb, y_lum, usable, weights, residuals, bright;
  std::vector<double> saved_usable;  // usable outside a fold's fit
  const float* obs = nullptr;
  Vec3d fitted_albedo = Vec3d::Zero(), fitted_specular = Vec3d::Zero();  // the last Fit's
  double brightness = 0, threshold = 0;
  double saturation_level = 0;  // the pixel's (PixelSaturation)
  bool dark = false;

  State(const PhotometricData& d, const PixelFitSettings& s) : data(d), settings(s), lights(d) {
    model.data = &d;
    model.lights = &lights;
    model.channels = s.color_residuals ? 3 : 1;
    if (s.known_ks) {
      model.known_ks =
          s.color_residuals ? *s.known_ks : Vec3d(internal::Luminance(*s.known_ks), 0, 0);
    }
    if (s.ks_prior && !s.known_ks) {
      model.ks_prior =
          s.color_residuals ? *s.ks_prior : Vec3d(internal::Luminance(*s.ks_prior), 0, 0);
      model.ks_prior_weight = s.ks_prior_weight;
    }
    model.shininess = s.shininess;
    model.ks_ridge = s.ks_ridge;
    if (!settings.shading_weights.offset.empty()) model.offset = &settings.shading_weights;
    model.model = s.model;
    // A known zero ks is no specular term: the Lambertian model, not a zero lobe.
    if (s.known_ks && s.known_ks->isZero()) model.model.lobe = reflectance::Lobe::kLambert;
    factors.reserve(d.images);
    trial.reserve(d.images);
    y_rgb.resize(3 * d.images);
    y_lum.resize(d.images);
    usable.resize(d.images);
    weights.resize(d.images);
    residuals.resize(3 * d.images);
    bright.reserve(d.images);
  }

  // Censoring weights from the residuals at the current factors, the coefficients eliminated
  // with the current weights: one weight per image (a shadow darkens every channel), decided on
  // the luminance of the residual.
  void Censor() {
    model.Residuals(factors, weights.data(), residuals.data());
    const int ch = model.channels;
    for (int j = 0; j < data.images; ++j) {
      const double r = ch == 1 ? residuals[j]
                               : internal::Luminance(Vec3d(residuals[3 * j], residuals[3 * j + 1],
                                                           residuals[3 * j + 2]));
      weights[j] = usable[j] *
                   internal::CensoredWeight(settings.censor_bright ? -std::abs(r) : r, threshold);
      if (weights[j] != 0 && !settings.shading_weights.empty())
        weights[j] *= settings.shading_weights.At(factors[j].diffuse.a);
    }
  }

  // Levenberg–Marquardt on the chart coordinates with fixed weights, from x (updated in place;
  // `factors` are the model's at x on entry and on return). The damping follows
  // ceres::TinySolver; every trial point is evaluated with its derivatives, so an accepted step
  // costs one run of the model, not two.
  int Minimize(Eigen::Vector2d& x) {
    // A relative cost change below this leaves the normal within ~1e-3 σ/kd of the optimum, far
    // inside the noise (on DiLiGenT cat 1e-12 spends twice the iterations for the same figures).
    const double kCostTolerance = 1e-6;
    PixelModel::NormalEquations eq = model.Reduce(factors, weights.data());
    double u = 1e-4, v = 2;
    int iterations = 0;
    bool moved = false;
    for (; iterations < settings.max_iterations; ++iterations) {
      Eigen::Matrix2d damped = eq.jtj;
      for (int i = 0; i < 2; ++i) damped(i, i) += u * std::clamp(eq.jtj(i, i), 1e-6, 1e32);
      const Eigen::Vector2d step = damped.ldlt().solve(eq.descent);
      // 1e-8 of the chart is ~1e-6 degrees: stopping there saves iterations that polish noise.
      if (!step.allFinite() || step.norm() < 1e-8) break;
      const Eigen::Vector2d x_new = x + step;
      model.Evaluate(x_new, &trial, weights.data(), true);
      const PixelModel::NormalEquations eq_new = model.Reduce(trial, weights.data());
      const double change = eq.cost - eq_new.cost;
      const double predicted = step.dot(eq.descent - 0.5 * eq.jtj * step);
      const double rho = change / predicted;
      if (rho > 0) {
        x = x_new;
        std::swap(factors, trial);
        eq = eq_new;
        moved = true;
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
    if (moved) model.Evaluate(x, &factors, weights.data(), false);
    return iterations;
  }
};

PixelFitter::PixelFitter(const PhotometricData& data, const PixelFitSettings& settings)
    : state_(std::make_unique<State>(data, settings)) {}

PixelFitter::~PixelFitter() = default;

const double* PixelFitter::luminance() const { return state_->y_lum.data(); }
const double* PixelFitter::usable() const { return state_->usable.data(); }
double PixelFitter::threshold() const { return state_->threshold; }
double PixelFitter::brightness() const { return state_->brightness; }
bool PixelFitter::dark() const { return state_->dark; }

bool PixelFitter::Prepare(std::size_t p) {
  State& st = *state_;
  const int k = st.data.images;
  st.obs = st.data.pixel(p);
  st.lights.At(p);
  st.bright.clear();
  double brightest = 0;
  const double saturation = PixelSaturation(st.obs, 3 * std::size_t(k), st.settings.saturation);
  st.saturation_level = saturation;
  for (int j = 0; j < k; ++j) {
    const Vec3d rgb(st.obs[3 * j], st.obs[3 * j + 1], st.obs[3 * j + 2]);
    // A near light that sends this point nothing (behind an LED) tells nothing of its normal.
    const bool lit = st.lights.lit(j);
    const bool saturated = rgb.maxCoeff() >= saturation || !lit;
    st.usable[j] = saturated ? 0.0 : 1.0;
    brightest = std::max(brightest, internal::Luminance(rgb));
    const Vec3d code =
        rgb.unaryExpr([&](double v) { return AtCodeMiddle(v, st.settings.code_offset); });
    const Vec3d y =
        lit ? Vec3d((code - st.settings.ambient_term).cwiseQuotient(st.lights.irradiance(j)))
            : Vec3d::Zero();
    for (int c = 0; c < 3; ++c) st.y_rgb[3 * j + c] = y[c];
    st.y_lum[j] = internal::Luminance(y);
    if (!saturated) st.bright.push_back(st.y_lum[j]);
  }
  // Dark as recorded: with a code offset or below the ambient term every value may be nonzero.
  st.dark = !(brightest > 1e-8) || !(*std::max_element(st.y_lum.begin(), st.y_lum.end()) > 1e-8);
  if (st.bright.size() < 3 || st.dark) return false;
  st.brightness = internal::BrightnessScale(st.bright);
  st.threshold = st.settings.shadow_threshold * st.brightness;
  st.model.y = st.model.channels == 1 ? st.y_lum.data() : st.y_rgb.data();
  if (st.model.offset) {
    // Each channel's share of the brightness: its sum over the usable observations against
    // their luminance's.
    double lum = 0;
    Vec3d rgb = Vec3d::Zero();
    for (int j = 0; j < k; ++j) {
      if (st.usable[j] == 0) continue;
      lum += st.y_lum[j];
      rgb += Vec3d(st.y_rgb[3 * j], st.y_rgb[3 * j + 1], st.y_rgb[3 * j + 2]);
    }
    for (int c = 0; c < 3; ++c) {
      st.model.offset_scale[c] = st.model.channels == 1 ? st.brightness
                                 : lum > 0              ? st.brightness * rgb[c] / lum
                                                        : 0.0;
    }
  }
  return true;
}

void PixelFitter::Fit(internal::PixelSolution& s, const double* lights) {
  State& st = *state_;
  const int k = st.data.images;
  // The lights left out are unusable for this fit only (kept in a member buffer: no allocation
  // per fit).
  if (lights) {
    st.saved_usable.assign(st.usable.begin(), st.usable.end());
    for (int j = 0; j < k; ++j) st.usable[j] *= lights[j] != 0 ? 1.0 : 0.0;
  }
  st.weights = st.usable;
  st.model.Center(s.normal);
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  st.model.Evaluate(x, &st.factors);
  // The censoring of the start, so the first round already leaves its shadows out.
  st.Censor();
  Vec3d normal = s.normal;
  for (int round = 0; round < st.settings.rounds; ++round) {
    s.iterations += st.Minimize(x);
    const Vec3d previous = normal;
    normal = st.model.Normal(x);
    // Reweighting can no longer move a normal that moved less than 0.01 degrees.
    if (round > 0 && previous.dot(normal) > std::cos(1e-2 * M_PI / 180)) break;
    st.Censor();
    // A chart far from its centre bends; re-centre it (the factors' derivatives change).
    if (x.norm() > 0.25 && round + 1 < st.settings.rounds) {
      st.model.Center(normal);
      x.setZero();
      st.model.Evaluate(x, &st.factors);
    }
  }
  s.normal = normal;
  // The RGB coefficients with the final weights, and the RMS difference between the usable
  // observations and the model (its factors combined by reflectance::CombineFactors, + Ia⊙ka).
  // Both of the observations as recorded, without the offsets: the offsets place the normal;
  // the coefficients are the Phong model's at it, what a render from them reproduces.
  std::vector<reflectance::LightFactors<double>>& f = st.values;
  f.resize(k);
  for (int j = 0; j < k; ++j) f[j] = {st.factors[j].diffuse.a, st.factors[j].specular.a};
  const auto coef = internal::EliminatedCoefficients<double>(
      f, 3, st.settings.known_ks ? st.settings.known_ks->data() : nullptr,
      [&](std::size_t j, int c) { return st.y_rgb[3 * j + c]; },
      [&](std::size_t j) { return st.weights[j]; },
      st.settings.ks_prior && !st.settings.known_ks ? st.settings.ks_prior->data() : nullptr,
      st.settings.ks_prior_weight, st.settings.ks_ridge);
  s.albedo = Vec3d(coef[0].kd, coef[1].kd, coef[2].kd);
  s.specular = st.model.model.lobe == reflectance::Lobe::kLambert
                   ? Vec3d::Zero()
                   : Vec3d(coef[0].ks, coef[1].ks, coef[2].ks);
  double sq = 0, cost = 0;
  int used = 0;
  for (int j = 0; j < k; ++j) {
    if (st.usable[j] == 0) continue;
    const double r = st.y_lum[j] - internal::Luminance(reflectance::CombineFactors<double>(
                                       f[j], Vec3d::Ones(), Vec3d::Ones(), s.albedo, s.specular));
    cost += internal::CensoredCost(st.settings.censor_bright ? -std::abs(r) : r, st.threshold);
    const Vec3d& e = st.lights.irradiance(j);
    // Against the observation as the fit saw it (code offset on, ambient term off: y_j ⊙ E_j),
    // in image units.
    const Vec3d y(st.y_rgb[3 * j], st.y_rgb[3 * j + 1], st.y_rgb[3 * j + 2]);
    sq +=
        (y.cwiseProduct(e) - reflectance::CombineFactors<double>(f[j], e, e, s.albedo, s.specular))
            .squaredNorm();
    used += 3;
  }
  s.residual = std::sqrt(sq / std::max(used, 1));
  s.cost = cost;
  st.fitted_albedo = s.albedo;
  st.fitted_specular = s.specular;
  // Copied back, not moved: usable() hands out this buffer.
  if (lights) std::copy(st.saved_usable.begin(), st.saved_usable.end(), st.usable.begin());
}

double PixelFitter::ImageCost(const double* lights) const {
  const State& st = *state_;
  const int k = st.data.images;
  // Every unsaturated observation, in image units: a light that sends this point nothing
  // (behind an LED) is predicted dark, so a surface placed where the lights miss it is not
  // excused its bright observations.
  std::vector<double> recorded(k, 0.0), bright;
  bright.reserve(k);
  for (int j = 0; j < k; ++j) {
    const Vec3d rgb(st.obs[3 * j], st.obs[3 * j + 1], st.obs[3 * j + 2]);
    if (rgb.maxCoeff() >= st.saturation_level || (lights && lights[j] == 0)) {
      recorded[j] = NAN;
      continue;
    }
    const Vec3d code =
        rgb.unaryExpr([&](double v) { return AtCodeMiddle(v, st.settings.code_offset); });
    recorded[j] = internal::Luminance(code - st.settings.ambient_term);
    bright.push_back(recorded[j]);
  }
  const double t = st.settings.shadow_threshold * internal::BrightnessScale(bright);
  double cost = 0;
  for (int j = 0; j < k; ++j) {
    if (std::isnan(recorded[j])) continue;
    const Vec3d& e = st.lights.irradiance(j);
    const double r = recorded[j] - internal::Luminance(reflectance::CombineFactors<double>(
                                       st.values[j], e, e, st.fitted_albedo, st.fitted_specular));
    cost += internal::CensoredCost(st.settings.censor_bright ? -std::abs(r) : r, t);
  }
  return cost / (t * t);
}

double PixelFitter::Diffuse(int j) const { return state_->values[j].diffuse; }

double PixelFitter::Predicted(int j) const {
  const State& st = *state_;
  return internal::Luminance(reflectance::CombineFactors<double>(
      st.values[j], Vec3d::Ones(), Vec3d::Ones(), st.fitted_albedo, st.fitted_specular));
}

}  // namespace iphong::solve
