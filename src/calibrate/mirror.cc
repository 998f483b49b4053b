// Light directions from the highlights on mirror spheres.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "calibrate/lights.h"
#include "core/parallel.h"
#include "core/timing.h"
#include "reflectance/phong.h"
#include "solve/photometric_data.h"

namespace iphong::calibrate {
namespace {

constexpr double kDeg = 180 / M_PI;

std::string Fixed(double v, int digits) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  return text;
}

double AngleDeg(const Vec3d& a, const Vec3d& b) {
  return kDeg * std::atan2(a.cross(b).norm(), a.dot(b));
}

// The light a mirror shows at a normal: the model's reflection of the view.
Vec3d MirrorLight(const Vec3d& normal, const Vec3d& view) {
  return reflectance::Reflect(normal, normal.dot(view), view);
}

Highlight FindHighlight(const ImageF& image, const SphereGeometry& sphere,
                        const MirrorOptions& options) {
  Highlight h;
  const SphereOutline& o = sphere.outline;
  const std::string where =
      "on the sphere at (" + Fixed(o.center_x_px, 0) + ", " + Fixed(o.center_y_px, 0) + ")";
  // The disc's pixels at least a pixel inside the outline: the rim mixes in the background.
  const int c0 = std::max(0, int(std::floor(o.center_x_px - o.radius_px)));
  const int c1 = std::min(image.width - 1, int(std::ceil(o.center_x_px + o.radius_px)));
  const int r0 = std::max(0, int(std::floor(o.center_y_px - o.radius_px)));
  const int r1 = std::min(image.height - 1, int(std::ceil(o.center_y_px + o.radius_px)));
  if (c1 < c0 || r1 < r0) {
    h.problem = "the sphere lies outside the image";
    return h;
  }
  const int bw = c1 - c0 + 1, bh = r1 - r0 + 1;
  cv::Mat value(bh, bw, CV_64F, cv::Scalar(-1));
  std::vector<double> values;
  std::vector<float> channel[3];
  const double inner = std::max(0.0, o.radius_px - 1);
  for (int r = r0; r <= r1; ++r) {
    for (int c = c0; c <= c1; ++c) {
      const double dx = c + 0.5 - o.center_x_px, dy = r + 0.5 - o.center_y_px;
      if (dx * dx + dy * dy > inner * inner) continue;
      const float* v = image.at(c, r);
      const double m = image.channels >= 3 ? std::max({v[0], v[1], v[2]}) : v[0];
      value.at<double>(r - r0, c - c0) = m;
      values.push_back(m);
      for (int k = 0; k < 3; ++k) channel[k].push_back(v[std::min(k, image.channels - 1)]);
    }
  }
  if (values.size() < 9) {
    h.problem = "the sphere is too small or outside the image";
    return h;
  }
  const double peak = *std::max_element(values.begin(), values.end());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  const double median = values[values.size() / 2];
  if (!(peak > 0) || peak < options.min_contrast * median) {
    h.problem = "no highlight " + where + ": its brightest pixel is " +
                (median > 0 ? Fixed(peak / median, 1) + "x its median" : "black") +
                " (the light is behind the sphere or off, or the sphere is not a mirror)";
    return h;
  }
  Rgb median_rgb;
  for (int k = 0; k < 3; ++k) {
    std::nth_element(channel[k].begin(), channel[k].begin() + channel[k].size() / 2,
                     channel[k].end());
    median_rgb[k] = channel[k][channel[k].size() / 2];
  }
  for (int r = r0; r <= r1; ++r) {
    for (int c = c0; c <= c1; ++c) {
      if (value.at<double>(r - r0, c - c0) < 0) continue;
      const float* v = image.at(c, r);
      for (int k = 0; k < 3; ++k) h.energy[k] += v[std::min(k, image.channels - 1)] - median_rgb[k];
    }
  }

  // Per highlight: a sphere whose values pass 1 is a float capture not clipped there.
  const double saturation = solve::SaturationLevel(options.saturation, peak);
  const double top = std::min(peak, saturation);
  const double t = options.threshold * top;
  const cv::Mat above = value >= t;
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(above, labels, stats, centroids, 8);
  std::vector<double> weight(count, 0);
  for (int r = 0; r < bh; ++r) {
    for (int c = 0; c < bw; ++c) {
      const int l = labels.at<int>(r, c);
      if (l > 0) weight[l] += std::min(value.at<double>(r, c), top) - t;
    }
  }
  const int best = int(std::max_element(weight.begin() + 1, weight.end()) - weight.begin());
  for (int l = 1; l < count; ++l) h.blobs += weight[l] >= 0.1 * weight[best];

  // The intensity-weighted mean of the reflected directions: the equal-area property makes it
  // the highlight's centre in directions (see lights.h), wherever on the sphere it is.
  Vec3d sum_dir = Vec3d::Zero();
  double sum_w = 0, sum_w2 = 0, sum_x = 0, sum_y = 0;
  struct Sample {
    Vec3d dir;
    double w;
  };
  std::vector<Sample> samples;
  for (int r = 0; r < bh; ++r) {
    for (int c = 0; c < bw; ++c) {
      if (labels.at<int>(r, c) != best) continue;
      const double v = value.at<double>(r, c);
      const double w = std::max(std::min(v, top) - t, 1e-12 * top);
      const double x = c0 + c + 0.5, y = r0 + r + 0.5;
      Vec3d normal, view, point;
      if (!sphere.At(x, y, &normal, &view, &point)) continue;
      const Vec3d dir = MirrorLight(normal, view);
      samples.push_back({dir, w});
      sum_dir += w * dir;
      sum_w += w;
      sum_w2 += w * w;
      sum_x += w * x;
      sum_y += w * y;
      ++h.pixels;
      h.saturated_pixels += v >= saturation;
    }
  }
  if (h.pixels == 0 || sum_dir.norm() == 0) {
    h.problem = "no highlight " + where + " (its bright pixels fall outside the sphere)";
    return h;
  }
  h.found = true;
  h.light_dir_cam = sum_dir.normalized();
  h.x_px = sum_x / sum_w;
  h.y_px = sum_y / sum_w;
  Vec3d normal, view;
  if (!sphere.At(h.x_px, h.y_px, &normal, &view, &h.point_cam)) h.point_cam = sphere.center_cam;
  double spread = 0;
  for (const Sample& s : samples) spread += s.w * std::pow(AngleDeg(s.dir, h.light_dir_cam), 2);
  h.spread_deg = std::sqrt(spread / sum_w);
  // A pixel's footprint in directions where the highlight is; the centre of n_eff pixels is
  // known to about a footprint / √(12 n_eff) (quantization, the error left on noise-free images).
  const double n_eff = sum_w * sum_w / sum_w2;
  double footprint = 0;
  Vec3d n1, v1, p1;
  int steps = 0;
  for (const Vec2d& d : {Vec2d(1, 0), Vec2d(0, 1), Vec2d(-1, 0), Vec2d(0, -1)}) {
    if (sphere.At(h.x_px + d.x(), h.y_px + d.y(), &n1, &v1, &p1)) {
      footprint += AngleDeg(MirrorLight(n1, v1), MirrorLight(normal, view));
      ++steps;
    }
  }
  footprint = steps > 0 ? footprint / steps : 2 * kDeg / o.radius_px;
  h.uncertainty_px = 1 / std::sqrt(12 * n_eff);
  h.uncertainty_deg = footprint * h.uncertainty_px;
  return h;
}

}  // namespace

std::string MirrorOptions::Check() const {
  if (!(threshold > 0 && threshold < 1)) return "the highlight threshold must be in (0, 1)";
  if (!(saturation > 0)) return "the saturation level must be positive";
  if (!(min_contrast >= 1)) return "the minimum contrast must be at least 1";
  if (!(same_light_deg >= 0)) return "same_light_deg must be non-negative";
  return "";
}

MirrorCalibration CalibrateMirror(const std::vector<const ImageF*>& images,
                                  const std::vector<SphereGeometry>& spheres,
                                  const MirrorOptions& options) {
  const auto start = Clock::now();
  if (std::string m = options.Check(); !m.empty()) throw std::invalid_argument(m);
  if (images.empty()) throw std::invalid_argument("no images");
  if (spheres.empty()) throw std::invalid_argument("no sphere");
  for (const ImageF* image : images) {
    if (image->width != images[0]->width || image->height != images[0]->height ||
        image->channels < 1) {
      throw std::invalid_argument("the images differ in size");
    }
  }
  MirrorCalibration result;
  result.spheres = spheres;
  const std::size_t k = images.size(), s_count = spheres.size();
  result.highlights.assign(k, std::vector<Highlight>(s_count));
  ParallelFor(0, k, 1, options.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t j = b; j < e; ++j)
      for (std::size_t s = 0; s < s_count; ++s)
        result.highlights[j][s] = FindHighlight(*images[j], spheres[s], options);
  });

  result.light_dir_cam.assign(k, Vec3d::Zero());
  bool any_saturated = false;
  for (std::size_t j = 0; j < k; ++j) {
    Vec3d sum = Vec3d::Zero();
    bool ok = true;
    for (const Highlight& h : result.highlights[j]) {
      ok &= h.found;
      sum += h.light_dir_cam;
      any_saturated |= h.saturated_pixels > 0;
      if (h.found && h.blobs > 1) {
        result.warnings.push_back(
            {int(j), -1,
             std::to_string(h.blobs) + " highlights on the sphere at (" + Fixed(h.x_px, 0) + ", " +
                 Fixed(h.y_px, 0) +
                 "): took the strongest (a second light, or an interreflection?)"});
      }
    }
    if (!ok) {
      result.failed.push_back(int(j));
      continue;
    }
    result.light_dir_cam[j] = sum.normalized();
  }
  if (!result.failed.empty()) {
    result.seconds = SecondsSince(start);
    return result;
  }

  // Two spheres: the reflected rays meet at a point light.
  const Vec3d middle =
      s_count == 2 ? 0.5 * (spheres[0].center_cam + spheres[1].center_cam) : spheres[0].center_cam;
  if (s_count == 2) {
    std::vector<Vec3d> positions(k);
    result.triangulation_gap.assign(k, 0);
    bool all = true;
    for (std::size_t j = 0; j < k && all; ++j) {
      const Highlight& a = result.highlights[j][0];
      const Highlight& b = result.highlights[j][1];
      double gap;
      positions[j] = ClosestPoint(a.point_cam, a.light_dir_cam, b.point_cam, b.light_dir_cam, &gap);
      result.triangulation_gap[j] = gap;
      // Rays closer to parallel than three standard errors meet wherever the noise puts them.
      const double parallax = AngleDeg(a.light_dir_cam, b.light_dir_cam);
      all = std::isfinite(gap) && gap < 0.1 * (positions[j] - middle).norm() &&
            parallax > 3 * (a.uncertainty_deg + b.uncertainty_deg);
    }
    if (all) {
      result.light_position_cam = positions;
      for (std::size_t j = 0; j < k; ++j)
        result.light_dir_cam[j] = (positions[j] - middle).normalized();
    } else {
      result.positions_note =
          "no point-light positions: the two spheres' reflected rays do not meet (the lights "
          "are distant, or the spheres' highlights disagree)";
      result.triangulation_gap.clear();
    }
  } else {
    result.positions_note = "no point-light positions: they need two spheres";
  }

  for (std::size_t j = 0; j < k; ++j) {
    const Vec3d& l = result.light_dir_cam[j];
    if (l.z() < 0) {
      result.warnings.push_back(
          {int(j), -1,
           "the light is behind the sphere's equator as the camera sees it (" +
               Fixed(90 - AngleDeg(l, Vec3d(0, 0, 1)), 1) +
               " deg elevation): it grazes what faces the camera"});
    }
    if (s_count == 2 && result.light_position_cam.empty()) {
      const double disagree =
          AngleDeg(result.highlights[j][0].light_dir_cam, result.highlights[j][1].light_dir_cam);
      if (disagree > 2) {
        result.warnings.push_back(
            {int(j), -1, "the two spheres disagree by " + Fixed(disagree, 1) + " deg"});
      }
    }
    for (const Highlight& h : result.highlights[j]) {
      // A clipped blob wider than ~5° in radius: a big source, or the exposure was too long.
      if (h.saturated_pixels > 0 && h.spread_deg > 5) {
        result.warnings.push_back(
            {int(j), -1,
             "the highlight is clipped over a large blob (" + std::to_string(h.saturated_pixels) +
                 " pixels, " + Fixed(h.spread_deg, 1) +
                 " deg RMS radius): its centre is less certain; shorten the exposure"});
      }
    }
    for (std::size_t i = 0; i < j; ++i) {
      const double apart = AngleDeg(result.light_dir_cam[i], l);
      if (apart < options.same_light_deg) {
        result.warnings.push_back(
            {int(i), int(j), "the same light (" + Fixed(apart, 2) + " deg apart)"});
      }
    }
  }

  result.light_intensities.assign(k, Rgb::Ones());
  if (!any_saturated) {
    Rgb mean = Rgb::Zero();
    for (std::size_t j = 0; j < k; ++j) {
      Rgb e = Rgb::Zero();
      for (const Highlight& h : result.highlights[j]) e += h.energy / double(s_count);
      result.light_intensities[j] = e;
      mean += e / double(k);
    }
    result.intensities_measured = (mean.array() > 0).all();
    for (std::size_t j = 0; j < k; ++j) {
      result.light_intensities[j] = result.intensities_measured
                                        ? Rgb(result.light_intensities[j].array() / mean.array())
                                        : Rgb::Ones();
    }
  }
  if (!result.intensities_measured) {
    result.warnings.push_back(
        {-1, -1,
         std::string(any_saturated ? "highlights are clipped" : "the highlights carry no energy") +
             ": intensities not measured (all 1 written); calibrate from a matte sphere, or "
             "run normals with --estimate-intensities"});
  }
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace iphong::calibrate
