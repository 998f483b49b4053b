// What a fitted model says about the capture: the kd of every pixel, the lobe as the data show it,
// and predicted and observed images.
#include <algorithm>
#include <cmath>

#include "material/internal.h"
#include "reflectance/material.h"
#include "solve/internal.h"

namespace iphong::material {

using reflectance::Lobe;

namespace internal {

std::vector<LobeBin> LobeBins(const Sample& s, const Coefficients& c, Lobe lobe,
                              const std::vector<unsigned char>& used) {
  std::vector<LobeBin> bins;
  const double ks_lum = solve::internal::Luminance(c.ks);
  if (lobe == Lobe::kLambert || !(ks_lum > 0) || !(c.shininess > 0)) return bins;
  // Out to three half widths at half maximum of the fitted lobe, at least 10°.
  const double half_width = std::acos(std::pow(0.5, 1 / c.shininess)) * 180 / M_PI;
  const double range = std::min(90.0, std::max(10.0, 3 * half_width));
  constexpr int kBins = 30;
  std::vector<double> sum(kBins, 0), sum2(kBins, 0);
  std::vector<std::size_t> n(kBins, 0);
  for (std::size_t p = 0; p < s.size(); ++p) {
    if (!c.kd_known[s.group[p]]) continue;
    for (int j = 0; j < s.lights; ++j) {
      const std::size_t i = p * s.lights + j;
      const double cosine = s.cosine(lobe, i);
      if (!used[i] || !(cosine > 0) || !(s.diffuse[i] > 0)) continue;
      const double angle = std::acos(std::min(1.0, cosine)) * 180 / M_PI;
      const int b = static_cast<int>(angle / range * kBins);
      if (b >= kBins) continue;
      const Vec3d& e = s.data->light_intensities[j];
      reflectance::LightFactors<double> diffuse_only;  // the model without its lobe
      diffuse_only.diffuse = s.diffuse[i];
      const Vec3d diffuse =
          c.ambient + reflectance::CombineFactors(diffuse_only, e, e, c.kd[s.group[p]], c.ks);
      const Vec3d y = Eigen::Vector3f(s.y(p, j)).cast<double>();
      const double v = solve::internal::Luminance(y - diffuse) /
                       solve::internal::Luminance(e.cwiseProduct(c.ks));
      sum[b] += v, sum2[b] += v * v, n[b] += 1;
    }
  }
  for (int b = 0; b < kBins; ++b) {
    if (n[b] == 0) continue;
    LobeBin bin;
    bin.angle_deg = (b + 0.5) * range / kBins;
    bin.count = n[b];
    bin.mean = sum[b] / n[b];
    const double var = n[b] > 1 ? std::max(0.0, sum2[b] / n[b] - bin.mean * bin.mean) : 0.0;
    bin.standard_error = std::sqrt(var / n[b]);
    bins.push_back(bin);
  }
  return bins;
}

// kd for every pixel with a normal, by chunks (the sample's pixels are a subset): the closed
// form with the chosen shared coefficients, censored once like the fit.
std::vector<Vec3d> PixelAlbedos(const solve::PhotometricData& data,
                                const std::vector<Vec3d>& normals,
                                const std::vector<std::size_t>& with_normal, Lobe lobe,
                                const Coefficients& c, const MaterialFitOptions& options) {
  std::vector<Vec3d> albedo(data.pixel_count(), Vec3d::Constant(NAN));
  constexpr std::size_t kChunk = 4096;
  for (std::size_t b = 0; b < with_normal.size(); b += kChunk) {
    Sample s;
    s.data = &data;
    s.lights = data.images;
    s.threads = options.threads;
    for (std::size_t i = b; i < std::min(with_normal.size(), b + kChunk); ++i) {
      s.pixel.push_back(with_normal[i]);
      s.normal.push_back(normals[with_normal[i]]);
      s.group.push_back(static_cast<int>(i - b));
    }
    s.groups = static_cast<int>(s.pixel.size());
    internal::FillFactors(s, options.saturation, options.shadow_threshold, options.threads);
    Coefficients fit = internal::AlbedoFit(s, lobe, c.ambient, c.ks, c.shininess, s.usable);
    std::vector<unsigned char> used;
    internal::Censor(s, lobe, fit, s.usable, &used);
    fit = internal::AlbedoFit(s, lobe, c.ambient, c.ks, c.shininess, used);
    for (std::size_t p = 0; p < s.size(); ++p) {
      if (fit.kd_known[p]) albedo[s.pixel[p]] = fit.kd[p];
    }
  }
  return albedo;
}

}  // namespace internal

ImageF PredictImage(const solve::PhotometricData& data, const std::vector<Vec3d>& normals_cam,
                    const ModelFit& model, const std::vector<Vec3d>& albedo, int light) {
  ImageF image(data.width, data.height, 3);
  reflectance::ModelOptions options;
  options.lobe = model.lobe;
  const Vec3d& e = data.light_intensities.at(light);
  const Vec3d& l = data.light_directions.at(light);
  const Vec3d view = solve::internal::ViewCam();
  for (std::size_t p = 0; p < data.pixel_count(); ++p) {
    if (normals_cam[p].squaredNorm() == 0 || !albedo[p].allFinite()) continue;
    reflectance::Material material;
    material.kd = albedo[p];
    material.ks = model.ks;
    material.shininess = model.shininess;
    const Vec3d value =
        model.ambient_term + reflectance::LightTerm<double>(normals_cam[p].normalized(), view, l, e,
                                                            e, material, options);
    for (int c = 0; c < 3; ++c) image.pixels[3 * std::size_t(data.pixels[p]) + c] = value[c];
  }
  return image;
}

ImageF ObservedImage(const solve::PhotometricData& data, int light) {
  ImageF image(data.width, data.height, 3);
  for (std::size_t p = 0; p < data.pixel_count(); ++p) {
    const float* y = data.pixel(p) + 3 * light;
    for (int c = 0; c < 3; ++c) image.pixels[3 * std::size_t(data.pixels[p]) + c] = y[c];
  }
  return image;
}

}  // namespace iphong::material
