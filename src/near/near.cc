#include "near/near.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include "core/parallel.h"
#include "core/timing.h"
#include "integrate/integrate.h"
#include "reflectance/material.h"
#include "solve/assemble.h"
#include "solve/model_choice.h"
#include "solve/pixel_fit.h"

namespace iphong::near {
namespace {

using solve::PhotometricData;

// The depth of pixel i's point (its distance along the axis, −z).
double DepthOf(const Vec3d& point) { return -point.z(); }

// Mean angle in degrees between two normal maps over the pixels both solved.
double MeanChangeDeg(const solve::NormalResult& a, const solve::NormalResult& b,
                     const PhotometricData& data) {
  double sum = 0;
  std::size_t n = 0;
  for (int p : data.pixels) {
    if (a.residual.pixels[p] < 0 || b.residual.pixels[p] < 0) continue;
    const float* x = a.normals.pixels.data() + 3 * static_cast<std::size_t>(p);
    const float* y = b.normals.pixels.data() + 3 * static_cast<std::size_t>(p);
    const double c =
        std::clamp(double(x[0]) * y[0] + double(x[1]) * y[1] + double(x[2]) * y[2], -1.0, 1.0);
    sum += std::acos(c) * 180 / M_PI;
    ++n;
  }
  return n ? sum / n : 0.0;
}

std::vector<Vec3d> NormalsPerPixel(const solve::NormalResult& r, const PhotometricData& data) {
  std::vector<Vec3d> out(data.pixel_count(), Vec3d(0, 0, 1));
  for (std::size_t i = 0; i < out.size(); ++i) {
    const float* n = r.normals.pixels.data() + 3 * static_cast<std::size_t>(data.pixels[i]);
    const Vec3d v(n[0], n[1], n[2]);
    if (v.allFinite() && v.norm() > 0.5) out[i] = v.normalized();
  }
  return out;
}

// The depth that integrating `normals` gives, per masked pixel, its free number set from `depth`
// (the geometric mean depth under perspective, the mean under an orthographic camera).
std::vector<double> IntegratedDepth(const solve::NormalResult& r, const PhotometricData& data,
                                    const geometry::HeightMapFrame& frame,
                                    const std::vector<double>& depth, const NearOptions& o) {
  Mask mask(data.width, data.height, false);
  for (int p : data.pixels) mask.inside[p] = 1;
  integrate::IntegrateOptions io;
  io.method = integrate::Method::kQuadratic;
  io.min_cos = o.min_cos;
  io.allow_back_facing = true;
  io.threads = o.normals.threads;
  double log_sum = 0, sum = 0;
  for (double d : depth) log_sum += std::log(d), sum += d;
  const double n = static_cast<double>(std::max<std::size_t>(1, depth.size()));
  if (frame.perspective) {
    io.perspective = true;
    io.intrinsics = {frame.fx, frame.fy, frame.cx, frame.cy};
    io.reference_depth = std::exp(log_sum / n);
  } else {
    io.pixel_size = frame.pixel_size;
  }
  const integrate::IntegrateResult ir = integrate::IntegrateNormals(r.normals, mask, io);
  std::vector<double> out(data.pixel_count());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double v = ir.height.pixels[static_cast<std::size_t>(data.pixels[i])];
    out[i] = frame.perspective ? v : sum / n - v;  // heights have mean 0 (each part)
    if (!std::isfinite(out[i])) out[i] = depth[i];
  }
  return out;
}

// The depth map scaled (perspective) or shifted (orthographic) so its mean distance changes by
// `factor`.
std::vector<double> WithFactor(const std::vector<double>& depth, double factor, bool perspective) {
  std::vector<double> out = depth;
  if (perspective) {
    for (double& d : out) d *= factor;
    return out;
  }
  double mean = 0;
  for (double d : depth) mean += d;
  mean /= static_cast<double>(std::max<std::size_t>(1, depth.size()));
  for (double& d : out) d += mean * (factor - 1);
  return out;
}

// Woodham's passes: more while its normals still move by this much, up to this many.
constexpr double kSettledDeg = 0.2;
constexpr int kMaxWoodhamPasses = 6;

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

}  // namespace

std::string NearOptions::Validate() const {
  if (auto m = normals.Validate(); !m.empty()) return m;
  if (!std::isfinite(distance) || distance < 0) return "distance must be finite and >= 0";
  if (max_passes < 1 || max_passes > 100) return "passes must be in 1..100";
  if (woodham_passes < 0 || woodham_passes > max_passes) {
    return "woodham passes must be in 0..passes";
  }
  if (!(tolerance_deg > 0) || !std::isfinite(tolerance_deg)) return "tolerance must be > 0";
  if (!(min_cos > 0 && min_cos < 1)) return "min_cos must be in (0, 1)";
  if (scale_sample < 10) return "scale sample must be >= 10";
  return "";
}

std::vector<Vec3d> SurfacePoints(const PhotometricData& data, const geometry::HeightMapFrame& frame,
                                 const std::vector<double>& depth) {
  std::vector<Vec3d> out(data.pixel_count());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const int p = data.pixels[i];
    out[i] = geometry::HeightMapPoint(frame, data.width, data.height, p % data.width,
                                      p / data.width, frame.perspective ? depth[i] : -depth[i]);
  }
  return out;
}

double GuessDistance(const std::vector<reflectance::Light>& lights) {
  // Where the LEDs point: the least-squares point of their axis lines.
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Vec3d b = Vec3d::Zero();
  int aimed = 0;
  for (const reflectance::Light& l : lights) {
    if (!(l.anisotropy > 0)) continue;
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - l.axis_cam * l.axis_cam.transpose();
    a += p;
    b += p * l.position_cam;
    ++aimed;
  }
  if (aimed >= 2) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a);
    if (eig.eigenvalues()[0] > 1e-3 * eig.eigenvalues()[2]) {
      const Vec3d x = a.ldlt().solve(b);
      if (x.allFinite() && x.z() < 0) return -x.z();
    }
  }
  // A dome: the centre of the sphere through the lights, |S − C|² = R², linear in C and
  // R² − |C|².
  if (lights.size() >= 5) {
    Eigen::MatrixXd m(lights.size(), 4);
    Eigen::VectorXd r(lights.size());
    for (std::size_t j = 0; j < lights.size(); ++j) {
      const Vec3d& s = lights[j].position_cam;
      m.row(j) << 2 * s.x(), 2 * s.y(), 2 * s.z(), 1;
      r[j] = s.squaredNorm();
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(m, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto sv = svd.singularValues();
    if (sv[3] > 1e-6 * sv[0]) {
      const Eigen::Vector4d x = svd.solve(r);
      const Vec3d c = x.head<3>();
      const double radius2 = x[3] + c.squaredNorm();
      if (c.allFinite() && radius2 > 0 && c.z() < 0) {
        const double radius = std::sqrt(radius2);
        double sq = 0;
        for (const reflectance::Light& l : lights) {
          const double e = (l.position_cam - c).norm() - radius;
          sq += e * e;
        }
        if (std::sqrt(sq / lights.size()) < 0.1 * radius) return -c.z();
      }
    }
  }
  return 0;
}

namespace {

// Observations where the lobe is under this fraction of its peak are the diffuse term's alone:
// under a tenth of a percent of a pixel's brightness for ks up to kd, below an 8-bit code.
constexpr double kDiffuseOnly = 1e-3;

// For each of `sample`'s pixels (in sub) and each light: 1 where the observation is the diffuse
// term's alone at `normals` with the surface points sub holds (every usable one for Lambert).
std::vector<double> DiffuseOnly(const PhotometricData& sub, const std::vector<Vec3d>& normals,
                                const std::vector<std::size_t>& sample,
                                const solve::PixelFitSettings& fit) {
  const int k = sub.images;
  std::vector<double> out(sample.size() * k, 1.0);
  if (fit.model.lobe == reflectance::Lobe::kLambert) return out;
  solve::PixelLights lights(sub);
  for (std::size_t i = 0; i < sample.size(); ++i) {
    lights.At(i);
    for (int j = 0; j < k; ++j) {
      out[i * k + j] =
          reflectance::SpecularLobe<double>(normals[sample[i]], lights.view(), lights.direction(j),
                                            fit.shininess, fit.model) < kDiffuseOnly;
    }
  }
  return out;
}

// The images' misfit on `sample` with the surface at `sub_depth` (per pixel of sub): each
// pixel's normal refitted from `normals` with the lights seen from its point, the censored costs
// in image units (solve::PixelFitter::ImageCost) summed. `sub` holds the sample's observations.
//
// Only the diffuse term places the surface: a pixel is fitted as Lambertian to the observations
// where its lobe is negligible (`diffuse`, decided once at the surface as it is, DiffuseOnly),
// and brighter ones are censored too. The lobe's coefficient is what a pixel's few highlights
// leave uncertain, and every way of estimating it biased the distance: the solver's pull of ks
// toward 0 (internal::kKsRidge) made a ring of lights round the lens look best 2 % nearer
// (cost 0.58 at the truth, 0.43 there); a free ks let the far tail of a lobe no light shows
// absorb a wrong distance's fall-off (0.4° under noise σ 0.002).
double SampleCost(PhotometricData& sub, const geometry::HeightMapFrame& frame,
                  const std::vector<double>& sub_depth, const std::vector<Vec3d>& normals,
                  const std::vector<std::size_t>& sample, const solve::PixelFitSettings& fit,
                  const std::vector<double>& diffuse, int threads) {
  sub.points_cam = SurfacePoints(sub, frame, sub_depth);
  solve::PixelFitSettings lambert = fit;
  lambert.model.lobe = reflectance::Lobe::kLambert;
  lambert.known_ks.reset();
  lambert.ks_prior.reset();
  lambert.censor_bright = true;
  const int k = sub.images;
  std::vector<double> each(sample.size(), 0.0);
  ParallelFor(0, sample.size(), 32, threads, [&](std::size_t b, std::size_t e) {
    solve::PixelFitter fitter(sub, lambert);
    for (std::size_t i = b; i < e; ++i) {
      const double* use = diffuse.data() + i * k;
      if (std::count(use, use + k, 1.0) < 3 || !fitter.Prepare(i)) continue;
      solve::internal::PixelSolution s;
      s.normal = normals[sample[i]];
      fitter.Fit(s, use);
      const double c = fitter.ImageCost(use);
      if (std::isfinite(c)) each[i] = c;
    }
  });
  double total = 0;
  for (double c : each) total += c;
  return total;
}

}  // namespace

double SurfaceCost(const PhotometricData& data, const geometry::HeightMapFrame& frame,
                   const std::vector<double>& depth, const std::vector<Vec3d>& normals,
                   const std::vector<std::size_t>& sample, const solve::PixelFitSettings& fit,
                   int threads) {
  PhotometricData sub = solve::SubsetObservations(data, sample);
  std::vector<double> sub_depth(sample.size());
  for (std::size_t i = 0; i < sample.size(); ++i) sub_depth[i] = depth[sample[i]];
  sub.points_cam = SurfacePoints(sub, frame, sub_depth);
  const std::vector<double> diffuse = DiffuseOnly(sub, normals, sample, fit);
  return SampleCost(sub, frame, sub_depth, normals, sample, fit, diffuse, threads);
}

double ChooseSurfaceOffset(const PhotometricData& data, const geometry::HeightMapFrame& frame,
                           const std::vector<double>& depth, const std::vector<Vec3d>& normals,
                           const std::vector<std::size_t>& sample,
                           const solve::PixelFitSettings& fit, double range, int threads) {
  PhotometricData sub = solve::SubsetObservations(data, sample);
  std::vector<double> sub_depth(sample.size());
  for (std::size_t i = 0; i < sample.size(); ++i) sub_depth[i] = depth[sample[i]];
  const double mean = Mean(depth);
  // Which observations are the diffuse term's is decided once, at the surface as it is, so every
  // candidate is scored on the same ones.
  sub.points_cam = SurfacePoints(sub, frame, sub_depth);
  const std::vector<double> diffuse = DiffuseOnly(sub, normals, sample, fit);
  const auto cost = [&](double factor) {
    std::vector<double> d = sub_depth;
    if (frame.perspective) {
      for (double& v : d) v *= factor;
    } else {
      for (double& v : d) v += mean * (factor - 1);
    }
    const double total = SampleCost(sub, frame, d, normals, sample, fit, diffuse, threads);
    return total;
  };
  // A grid of factors from 1/range to range in steps of at most √2, then golden section in the
  // best one's bracket.
  const int steps = std::max(4, static_cast<int>(std::ceil(2 * std::log2(range))));
  const double step = std::pow(range, 1.0 / steps);
  double best = 1, best_cost = cost(1.0);
  for (int i = -steps; i <= steps; ++i) {
    if (i == 0) continue;
    const double f = std::pow(step, i);
    const double c = cost(f);
    if (c < best_cost) best = f, best_cost = c;
  }
  double lo = std::log(best / step), hi = std::log(best * step);
  const double g = (std::sqrt(5.0) - 1) / 2;
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = cost(std::exp(x1)), f2 = cost(std::exp(x2));
  // To 0.05 % of the distance: a surface 1 % off tilts the normals a ring of lights shows by
  // a tenth of a degree or more.
  while (hi - lo > 5e-4) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = cost(std::exp(x1));
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = cost(std::exp(x2));
    }
  }
  const double x = f1 < f2 ? x1 : x2;
  return std::min(f1, f2) < best_cost ? std::exp(x) : best;
}

namespace {

// The loop of near.h on one capture: its data (surface points moved as the loop goes), frame,
// options and the sample whose fits place the surface.
class Loop {
 public:
  Loop(PhotometricData data, const geometry::HeightMapFrame& frame, const NearOptions& o)
      : data_(std::move(data)), frame_(frame), o_(o) {
    data_.perspective = frame.perspective;
    sample_ = solve::SpreadIndices(data_.pixel_count(),
                                   std::min<int>(o.scale_sample, int(data_.pixel_count())));
    woodham_ = o.normals;
    woodham_.model = reflectance::Lobe::kLambert;
    woodham_.material_known = false;
    // Before the object's lobe is known the surface is placed by Lambertian fits that leave
    // highlights out as they leave shadows out (as Woodham drops the brightest tenth).
    lambert_fit_ = solve::internal::FitSettingsOf(woodham_);
    lambert_fit_.model.lobe = reflectance::Lobe::kLambert;
    lambert_fit_.censor_bright = true;
  }

  void Say(const std::string& line) const {
    if (o_.log) o_.log(line);
  }

  // The ambient term the surface is placed with while the model is not chosen yet (the plan
  // then chooses its own with the lobe): the estimate (solve::EstimateAmbient) or none, whichever
  // fits the images better at the current surface. A constant left in the observations is
  // explained by the fall-off of lights at a wrong distance (a dome's sphere went from 464 to
  // 212 mm under an ambient of 1 % of its brightness).
  void ChooseAmbient() {
    if (o_.normals.material_known || !o_.normals.ambient_term.isZero()) return;
    const Vec3d ambient = solve::EstimateAmbient(data_);
    if (ambient.isZero()) return;
    double best = INFINITY;
    Vec3d chosen = Vec3d::Zero();
    for (const Vec3d& reading : {Vec3d(Vec3d::Zero()), ambient}) {
      woodham_.ambient_term = reading;
      lambert_fit_.ambient_term = reading;
      const solve::NormalResult w = solve::EstimateNormals(data_, woodham_);
      const double c = SurfaceCost(data_, frame_, depth_, NormalsPerPixel(w, data_), sample_,
                                   lambert_fit_, o_.normals.threads);
      if (c < best) best = c, chosen = reading;
    }
    woodham_.ambient_term = chosen;
    lambert_fit_.ambient_term = chosen;
  }

  void Place(const std::vector<double>& depth) {
    depth_ = depth;
    data_.points_cam = SurfacePoints(data_, frame_, depth_);
    solve::SetReferenceLights(data_, solve::MeanPoint(data_));
  }

  // Woodham's normals at the current surface, the surface they integrate to (its free number from
  // the current one) and that surface's misfit.
  double WoodhamSurface(std::vector<Vec3d>* normals = nullptr) {
    const solve::NormalResult w = solve::EstimateNormals(data_, woodham_);
    const std::vector<Vec3d> n = NormalsPerPixel(w, data_);
    Place(IntegratedDepth(w, data_, frame_, depth_, o_));
    if (normals) *normals = n;
    return SurfaceCost(data_, frame_, depth_, n, sample_, lambert_fit_, o_.normals.threads);
  }

  // Starts for the loop when nothing says where the object is: the surfaces of a grid of
  // distances (factors of 2 up to 16 either way of `distance`), each local minimum of their
  // misfit refined by two rounds of Woodham, integration and the surface's distance; by misfit.
  std::vector<std::pair<double, std::vector<double>>> Scan(double distance) {
    std::vector<std::pair<double, std::vector<double>>> grid, minima;
    Place(std::vector<double>(data_.pixel_count(), distance));
    ChooseAmbient();
    for (int i = -4; i <= 4; ++i) {
      Place(std::vector<double>(data_.pixel_count(), distance * std::pow(2.0, i)));
      const double c = WoodhamSurface();
      grid.emplace_back(c, depth_);
    }
    for (std::size_t i = 0; i < grid.size(); ++i) {
      const bool minimum = (i == 0 || grid[i].first <= grid[i - 1].first) &&
                           (i + 1 == grid.size() || grid[i].first <= grid[i + 1].first);
      if (!minimum) continue;
      Place(grid[i].second);
      double c = grid[i].first;
      for (int round = 0; round < 2; ++round) {
        std::vector<Vec3d> normals;
        WoodhamSurface(&normals);
        const double f = ChooseSurfaceOffset(data_, frame_, depth_, normals, sample_, lambert_fit_,
                                             std::sqrt(2.0), o_.normals.threads);
        Place(WithFactor(depth_, f, frame_.perspective));
        c = SurfaceCost(data_, frame_, depth_, normals, sample_, lambert_fit_, o_.normals.threads);
      }
      minima.emplace_back(c, depth_);
    }
    std::sort(minima.begin(), minima.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    return minima;
  }

  // The passes of near.h from the surface `depth`; `cost` receives the final surface's misfit
  // under the model the run chose.
  // `warm_plan`: the model is chosen from the last Woodham pass's normals (solve::PlanNormals
  // with starts) instead of searching: a start only compared with another.
  NearResult Run(const std::vector<double>& depth, double* cost, bool warm_plan = false) {
    Place(depth);
    ChooseAmbient();
    const std::size_t pixels = data_.pixel_count();
    NearResult result;
    int woodham_passes = o_.woodham_passes;
    std::optional<solve::NormalPlan> plan;
    bool replanned = false;
    int refines = 0;
    solve::NormalResult last;
    solve::PixelFitSettings fit = lambert_fit_;
    for (int pass = 0; pass < o_.max_passes; ++pass) {
      const auto pass_start = Clock::now();
      NearPass record;
      solve::NormalResult now;
      if (pass < woodham_passes) {
        record.kind = "woodham";
        now = solve::EstimateNormals(data_, woodham_);
      } else if (!plan) {
        record.kind = "solve";
        const std::vector<std::size_t> plan_sample =
            solve::PlanSampleIndices(pixels, o_.normals.plan_sample);
        std::vector<Vec3d> starts;
        if (warm_plan && pass > 0) {
          const std::vector<Vec3d> all = NormalsPerPixel(last, data_);
          for (std::size_t i : plan_sample) starts.push_back(all[i]);
        }
        plan = solve::PlanNormals(
            plan_sample.size() == pixels ? data_ : solve::SubsetObservations(data_, plan_sample),
            o_.normals, starts.empty() ? nullptr : &starts);
        now = solve::SolveNormalsWithPlan(data_, *plan);
        std::vector<Vec3f> sample_ks;
        solve::AppendSampleSpecular(now, data_, plan_sample, sample_ks);
        solve::FinishNormals(now, *plan, sample_ks);
        // A Lambertian plan keeps the fits that leave highlights out, as Woodham does.
        if (plan->options.model != reflectance::Lobe::kLambert) {
          fit = solve::internal::PlanFitSettings(*plan);
        }
      } else {
        record.kind = "refine";
        now = solve::RefineNormalsWithPlan(data_, *plan, last);
      }
      record.change_deg = pass == 0 ? 0.0 : MeanChangeDeg(last, now, data_);
      // The surface these normals make, at the distance their own fits choose.
      const std::vector<Vec3d> normals = NormalsPerPixel(now, data_);
      const std::vector<double> shape = IntegratedDepth(now, data_, frame_, depth_, o_);
      const double f =
          ChooseSurfaceOffset(data_, frame_, shape, normals, sample_, fit, 2, o_.normals.threads);
      Place(WithFactor(shape, f, frame_.perspective));
      record.distance = Mean(depth_);
      record.seconds = SecondsSince(pass_start);
      result.passes.push_back(record);
      char line[200];
      std::snprintf(line, sizeof line,
                    "pass %d (%s): normals moved %.3f deg, distance %.4g, %.2f s", pass + 1,
                    record.kind.c_str(), record.change_deg, record.distance, record.seconds);
      Say(line);
      last = std::move(now);
      result.last_change_deg = record.change_deg;
      // A loop whose normals stopped settling (the surface's distance trading a fraction of a
      // percent back and forth) is done too, though not below the tolerance.
      const bool stalled =
          record.kind == "refine" && refines >= 3 &&
          record.change_deg >= 0.9 * result.passes[result.passes.size() - 2].change_deg;
      if (record.kind == "refine") ++refines;
      if (record.kind == "refine" && (record.change_deg < o_.tolerance_deg || stalled)) {
        // The model was chosen on the surface Woodham's normals gave; chosen again (warm: from
        // these normals) on the settled surface, and refined further if it changed.
        if (!replanned && solve::NeedsPlanSample(o_.normals)) {
          replanned = true;
          const auto replan_start = Clock::now();
          const std::vector<std::size_t> plan_sample =
              solve::PlanSampleIndices(pixels, o_.normals.plan_sample);
          const std::vector<Vec3d> all = NormalsPerPixel(last, data_);
          std::vector<Vec3d> starts;
          for (std::size_t i : plan_sample) starts.push_back(all[i]);
          solve::NormalPlan again = solve::PlanNormals(
              solve::SubsetObservations(data_, plan_sample), o_.normals, &starts);
          const solve::ModelCandidate& a = plan->model_choice.chosen;
          const solve::ModelCandidate& b = again.model_choice.chosen;
          // Only the lobe is asked again: it is what a surface a little off can bend (a lobe
          // that imitates the wrong lights' fall-off). The rest — the ks prior, the ambient term,
          // the codes' reading — is the first plan's unless the lobe changed.
          const bool same =
              a.lobe == b.lobe && std::abs(std::log(a.shininess / b.shininess)) < 0.05;
          char note[200];
          std::snprintf(note, sizeof note,
                        "model chosen again on the settled surface: %s %.3g (was %s %.3g), %.2f s",
                        reflectance::LobeName(b.lobe).c_str(), b.shininess,
                        reflectance::LobeName(a.lobe).c_str(), a.shininess,
                        SecondsSince(replan_start));
          Say(note);
          if (!same) {
            plan = std::move(again);
            if (plan->options.model != reflectance::Lobe::kLambert) {
              fit = solve::internal::PlanFitSettings(*plan);
            } else {
              fit = lambert_fit_;
            }
            refines = 0;
            continue;
          }
        }
        result.converged = !stalled;
        break;
      }
      // Woodham's passes go on while the surface still moves (each costs little), so the model
      // is chosen on the surface Woodham's normals settle on.
      if (record.kind == "woodham" && pass + 1 == woodham_passes && pass + 2 < o_.max_passes &&
          (pass == 0 || record.change_deg > kSettledDeg) && woodham_passes < kMaxWoodhamPasses) {
        ++woodham_passes;
      }
    }
    if (plan) {
      // The whole-object summaries (the object's ks, the notes) of the final pass's pixels.
      const std::vector<std::size_t> plan_sample =
          solve::PlanSampleIndices(pixels, o_.normals.plan_sample);
      std::vector<Vec3f> sample_ks;
      solve::AppendSampleSpecular(last, data_, plan_sample, sample_ks);
      solve::FinishNormals(last, *plan, sample_ks);
    }
    if (cost) {
      *cost = SurfaceCost(data_, frame_, depth_, NormalsPerPixel(last, data_), sample_, fit,
                          o_.normals.threads);
    }
    result.normals = std::move(last);
    result.distance = Mean(depth_);
    result.depth = ImageF(data_.width, data_.height, 1);
    result.points = ImageF(data_.width, data_.height, 3);
    for (std::size_t i = 0; i < pixels; ++i) {
      const std::size_t p = static_cast<std::size_t>(data_.pixels[i]);
      result.depth.pixels[p] = static_cast<float>(DepthOf(data_.points_cam[i]));
      for (int c = 0; c < 3; ++c) {
        result.points.pixels[3 * p + c] = static_cast<float>(data_.points_cam[i][c]);
      }
    }
    return result;
  }

 private:
  PhotometricData data_;
  geometry::HeightMapFrame frame_;
  const NearOptions& o_;
  std::vector<std::size_t> sample_;
  solve::NormalOptions woodham_;
  solve::PixelFitSettings lambert_fit_;
  std::vector<double> depth_;
};

// Two starts whose misfits are within this factor are both run to the end: a ring of lights
// leaves the distance weakly determined, and before the lobe is known a shiny object's misfit
// is mostly its highlights, left out alike at either distance.
constexpr double kAmbiguousStarts = 1.25;

}  // namespace

NearResult SolveNearLights(PhotometricData data, const geometry::HeightMapFrame& frame,
                           const NearOptions& o) {
  const auto start = Clock::now();
  if (auto m = o.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = frame.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (!data.near()) throw std::invalid_argument("near-light solve without point lights");
  if (data.pixel_count() == 0) throw std::invalid_argument("no pixel to solve");
  const std::size_t pixels = data.pixel_count();
  const double guess = o.distance > 0 ? o.distance : GuessDistance(data.point_lights);
  std::vector<double> far;
  for (const reflectance::Light& l : data.point_lights) far.push_back(l.position_cam.norm());
  std::nth_element(far.begin(), far.begin() + far.size() / 2, far.end());
  const double lights_distance = std::max(far[far.size() / 2], 1e-6);
  Loop loop(std::move(data), frame, o);
  NearResult result;
  if (guess > 0) {
    result = loop.Run(std::vector<double>(pixels, guess), nullptr);
  } else {
    // Nothing in the lights' layout says where the object is (a ring of lights in one plane):
    // the images say, from around the lights' own median distance from the camera.
    const auto starts = loop.Scan(lights_distance);
    char line[200];
    for (const auto& [cost, depth] : starts) {
      std::snprintf(line, sizeof line, "start at distance %.4g: misfit %.4g", Mean(depth), cost);
      loop.Say(line);
    }
    // Another start about as good is run too, its model chosen from its own Woodham normals
    // (warm: the search of the hemisphere is what the first run's choice costs).
    double best_cost = INFINITY;
    for (std::size_t i = 0; i < starts.size(); ++i) {
      if (i > 0 && !(starts[i].first <= kAmbiguousStarts * starts[0].first)) break;
      double cost = 0;
      NearResult r = loop.Run(starts[i].second, &cost, i > 0);
      std::snprintf(line, sizeof line, "from distance %.4g: %.4g, misfit %.4g",
                    Mean(starts[i].second), r.distance, cost);
      loop.Say(line);
      if (cost < best_cost) best_cost = cost, result = std::move(r);
    }
    result.distance_from_images = true;
  }
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace iphong::near
