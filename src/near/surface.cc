#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/parallel.h"
#include "integrate/integrate.h"
#include "near/internal.h"
#include "near/near.h"
#include "reflectance/lighting.h"
#include "reflectance/phong.h"
#include "solve/model_choice.h"
#include "solve/pixel_fit.h"

namespace iphong::near {
namespace internal {

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

namespace {

// The mean over (up to 2000 of) the pixels of the larger over the lights of the turn of the
// direction toward light j plus |ln| of its irradiance ratio, from lights0 seen from points0 to
// lights1 seen from points1 (degrees).
double LightsChange(const std::vector<reflectance::Light>& lights0,
                    const std::vector<Vec3d>& points0,
                    const std::vector<reflectance::Light>& lights1,
                    const std::vector<Vec3d>& points1) {
  // A mean to a few per cent: pixels spread over the object, not all of them (each costs two
  // looks at every light).
  const std::vector<std::size_t> spread = solve::SpreadIndices(points0.size(), 2000);
  double sum = 0;
  for (const std::size_t i : spread) {
    double largest = 0;
    for (std::size_t j = 0; j < lights0.size(); ++j) {
      Vec3d l0, l1, e0, e1, unused;
      const bool seen0 = reflectance::LightAt(lights0[j], points0[i], &l0, &e0, &unused);
      const bool seen1 = reflectance::LightAt(lights1[j], points1[i], &l1, &e1, &unused);
      const double a = seen0 ? e0.maxCoeff() : 0.0, b = seen1 ? e1.maxCoeff() : 0.0;
      if ((a > 0) != (b > 0)) {
        largest = std::max(largest, M_PI / 2);
      } else if (a > 0) {
        const double turn = std::atan2(l0.cross(l1).norm(), l0.dot(l1));
        largest = std::max(largest, turn + std::abs(std::log(b / a)));
      }
    }
    sum += largest;
  }
  return sum / static_cast<double>(spread.size()) * 180 / M_PI;
}

}  // namespace

double LightsMovedDeg(const solve::PhotometricData& data, const std::vector<Vec3d>& points) {
  if (points.size() != data.points_cam.size()) {
    throw std::invalid_argument("LightsMovedDeg: " + std::to_string(points.size()) +
                                " points for " + std::to_string(data.points_cam.size()));
  }
  if (data.point_lights.empty() || points.empty()) return 0.0;  // distant lights do not move
  return LightsChange(data.point_lights, data.points_cam, data.point_lights, points);
}

double LightsChangedDeg(const solve::PhotometricData& a, const solve::PhotometricData& b) {
  if (a.points_cam.size() != b.points_cam.size() ||
      a.point_lights.size() != b.point_lights.size()) {
    throw std::invalid_argument("LightsChangedDeg: " + std::to_string(a.points_cam.size()) +
                                " points and " + std::to_string(a.point_lights.size()) +
                                " point lights against " + std::to_string(b.points_cam.size()) +
                                " and " + std::to_string(b.point_lights.size()));
  }
  if (a.point_lights.empty() || a.points_cam.empty()) return 0.0;
  return LightsChange(a.point_lights, a.points_cam, b.point_lights, b.points_cam);
}

std::vector<Vec3d> NormalsPerPixel(const solve::NormalResult& r,
                                   const solve::PhotometricData& data) {
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
                                    const std::vector<double>& depth, double min_cos, int threads,
                                    std::size_t max_pixels) {
  Mask mask(data.width, data.height, false);
  for (int p : data.pixels) mask.inside[p] = 1;
  integrate::IntegrateOptions io;
  io.method = integrate::Method::kQuadratic;
  io.min_cos = min_cos;
  io.allow_back_facing = true;
  io.threads = threads;
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
  int factor = 1;
  if (max_pixels > 0 && !frame.perspective) {
    while (data.pixels.size() > max_pixels * factor * factor) factor *= 2;
  }
  const integrate::IntegrateResult ir =
      integrate::IntegrateNormalsCoarse(r.normals, mask, io, factor);
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

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

}  // namespace internal

using solve::PhotometricData;
using namespace internal;

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
                           const solve::PixelFitSettings& fit, double range, int threads,
                           double min_distance, double max_distance) {
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
  // The factors allowed: within `range` either way, and the mean distance within its bounds.
  const double lowest = std::max(1 / range, min_distance / mean);
  const double highest = std::min(range, max_distance / mean);
  if (!(lowest < highest)) return std::clamp(1.0, lowest, highest);
  // A grid of factors over that span in steps of at most √2, then golden section in the best
  // one's bracket.
  const double span = std::log(highest / lowest);
  const int steps = std::max(8, static_cast<int>(std::ceil(span / std::log(std::sqrt(2.0)))));
  const double step = std::exp(span / steps);
  double best = std::clamp(1.0, lowest, highest), best_cost = cost(best);
  for (int i = 0; i <= steps; ++i) {
    const double f = lowest * std::pow(step, i);
    const double c = cost(f);
    if (c < best_cost) best = f, best_cost = c;
  }
  double lo = std::log(std::max(best / step, lowest)),
         hi = std::log(std::min(best * step, highest));
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

}  // namespace iphong::near
