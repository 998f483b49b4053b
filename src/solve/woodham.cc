#include "solve/woodham.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "reflectance/material.h"

namespace iphong::solve {

using internal::PixelSolution;
using internal::PixelStatus;

Eigen::Matrix3Xd WoodhamPseudoInverse(const PhotometricData& data) {
  Eigen::Matrix3Xd l(3, data.images);
  for (int j = 0; j < data.images; ++j) l.col(j) = data.light_directions[j];
  const Eigen::Matrix3d ata = l * l.transpose();
  if (Eigen::LDLT<Eigen::Matrix3d>(ata).rcond() < 1e-9) return Eigen::Matrix3Xd();  // degenerate
  return ata.inverse() * l;
}

PixelSolution Woodham(const PhotometricData& data, std::size_t p, const WoodhamSettings& o,
                      const Eigen::Matrix3Xd& pinv, std::vector<std::pair<double, int>>& order,
                      PixelLights& lights, bool with_residual) {
  const int k = data.images;
  const float* obs = data.pixel(p);
  lights.At(p);
  const double saturation = PixelSaturation(obs, 3 * std::size_t(k), o.saturation);
  auto clipped = [&](int j) {
    return std::max({obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]}) >= saturation;
  };
  order.clear();
  double brightest = 0;
  int clipped_count = 0;
  for (int j = 0; j < k; ++j) {
    // A near light that sends the point nothing is left out (it sorts first, among the dark).
    if (!lights.lit(j)) continue;
    const Vec3d rgb(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]);
    const double g =
        internal::Luminance((rgb - o.ambient_term).cwiseQuotient(lights.irradiance(j)));
    order.emplace_back(g, j);
    brightest = std::max(brightest, g);
    clipped_count += clipped(j);
  }
  const int seen = static_cast<int>(order.size());  // every lit observation, clipped or not
  if (clipped_count > 0 && seen - clipped_count >= 3) {
    order.erase(std::remove_if(order.begin(), order.end(),
                               [&](const std::pair<double, int>& e) { return clipped(e.second); }),
                order.end());
  }
  const int lit = static_cast<int>(order.size());
  PixelSolution s;
  if (!(brightest > 1e-8)) {
    s.status = PixelStatus::kDark;
    return s;
  }
  // The fractions are of every lit observation, so a pixel's shadows are dropped as they would be
  // unclipped; the clipped ones, the brightest in truth, count toward the bright fraction.
  int first = static_cast<int>(std::floor(o.discard_dark * seen));
  int last =
      lit - std::max(0, static_cast<int>(std::floor(o.discard_bright * seen)) - (seen - lit));
  if (last - first < 3) {
    first = 0;
    last = lit;
  }
  Vec3d b;
  if (first == 0 && last == k && pinv.cols() == k && !data.near()) {
    b = Vec3d::Zero();
    for (int j = 0; j < k; ++j) b += pinv.col(order[j].second) * order[j].first;
  } else {
    // Only the two cut-offs matter, not the full order: two selections, O(K).
    if (first > 0) std::nth_element(order.begin(), order.begin() + first, order.end());
    if (last < lit) std::nth_element(order.begin() + first, order.begin() + last, order.end());
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Vec3d atb = Vec3d::Zero();
    for (int i = first; i < last; ++i) {
      const Vec3d& l = lights.direction(order[i].second);
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
  for (int i = first; i < last; ++i) {
    const int j = order[i].second;
    const double nl = s.normal.dot(lights.direction(j));
    if (nl <= 0) continue;
    const Vec3d rgb = (Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]) - o.ambient_term)
                          .cwiseQuotient(lights.irradiance(j));
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
  double sq = 0;
  int used = 0;
  for (int i = first; i < last; ++i) {
    const int j = order[i].second;
    const Vec3d& e = lights.irradiance(j);
    const Vec3d predicted = o.ambient_term + reflectance::LightTerm<double>(s.normal, lights.view(),
                                                                            lights.direction(j), e,
                                                                            e, lambertian, lambert);
    sq += (Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]) - predicted).squaredNorm();
    used += 3;
  }
  s.residual = std::sqrt(sq / std::max(used, 1));
  return s;
}

}  // namespace iphong::solve
