// Spheres in a mask: regions, their outlines, circles and cones fitted to them.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "calibrate/lights.h"
#include "geometry/height_map.h"

namespace iphong::calibrate {
namespace {

std::string Round1(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", v);
  return text;
}

// Algebraic (Kåsa) circle, then Gauss-Newton on the geometric distances: the algebraic fit is
// biased toward small circles when only an arc is visible.
void FitCircle(const std::vector<Vec2d>& points, double* cx, double* cy, double* r, double* rms) {
  Eigen::MatrixX3d a(points.size(), 3);
  Eigen::VectorXd b(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    a.row(i) << 2 * points[i].x(), 2 * points[i].y(), 1;
    b(i) = points[i].squaredNorm();
  }
  const Eigen::Vector3d s = a.colPivHouseholderQr().solve(b);
  Eigen::Vector3d p(s(0), s(1), std::sqrt(std::max(0.0, s(2) + s(0) * s(0) + s(1) * s(1))));
  for (int iteration = 0; iteration < 20; ++iteration) {
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    for (const Vec2d& q : points) {
      const Vec2d d = q - p.head<2>();
      const double dist = std::max(d.norm(), 1e-12);
      const Eigen::Vector3d j(-d.x() / dist, -d.y() / dist, -1);
      const double res = dist - p(2);
      jtj += j * j.transpose();
      jtr += j * res;
    }
    const Eigen::Vector3d step = jtj.ldlt().solve(-jtr);
    p += step;
    if (step.norm() < 1e-9) break;
  }
  double sum = 0;
  for (const Vec2d& q : points) sum += std::pow((q - p.head<2>()).norm() - p(2), 2);
  *cx = p(0);
  *cy = p(1);
  *r = p(2);
  *rms = std::sqrt(sum / points.size());
}

double VisibleFraction(const SphereOutline& s, int width, int height) {
  int visible = 0;
  for (int i = 0; i < 720; ++i) {
    const double a = i * M_PI / 360;
    const double x = s.center_x_px + s.radius_px * std::cos(a);
    const double y = s.center_y_px + s.radius_px * std::sin(a);
    visible += x >= 0 && y >= 0 && x <= width && y <= height;
  }
  return visible / 720.0;
}

}  // namespace

std::string CheckCircle(const SphereOutline& circle, int width, int height) {
  if (!(circle.radius_px > 0) || !std::isfinite(circle.radius_px) ||
      !std::isfinite(circle.center_x_px) || !std::isfinite(circle.center_y_px)) {
    return "a circle needs a finite centre and a radius > 0";
  }
  if (VisibleFraction(circle, width, height) < 0.5) {
    return "the circle (" + Round1(circle.center_x_px) + ", " + Round1(circle.center_y_px) +
           ", r " + Round1(circle.radius_px) + ") lies mostly outside the " +
           SizeText(width, height) + " images";
  }
  return "";
}

std::string Intrinsics::Check() const {
  if (fx == 0 && fy == 0) return "";
  // As every scale: a focal length of 1e300 px made every light the same direction.
  if (!geometry::ScaleInRange(fx) || !geometry::ScaleInRange(fy) || !std::isfinite(cx) ||
      !std::isfinite(cy)) {
    return "intrinsics need fx, fy between 1e-12 and 1e12 and a finite principal point";
  }
  return "";
}

std::string SphereSearch::Check() const {
  if (max_spheres < 1) return "max_spheres must be at least 1";
  if (!(min_radius_px > 0)) return "min_radius_px must be positive";
  if (!(max_rms_ratio > 0)) return "max_rms_ratio must be positive";
  return "";
}

std::vector<SphereOutline> FindSpheres(const Mask& mask, const SphereSearch& search,
                                       std::vector<std::string>* warnings) {
  if (std::string m = search.Check(); !m.empty()) throw std::invalid_argument(m);
  if (mask.width <= 0 || mask.height <= 0) throw std::invalid_argument("the mask is empty");
  const cv::Mat binary(mask.height, mask.width, CV_8U,
                       const_cast<unsigned char*>(mask.inside.data()));
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(binary != 0, labels, stats, centroids, 8);
  struct Region {
    int label, area;
  };
  std::vector<Region> regions;
  for (int l = 1; l < count; ++l) {
    const int area = stats.at<int>(l, cv::CC_STAT_AREA);
    if (area >= M_PI * search.min_radius_px * search.min_radius_px) regions.push_back({l, area});
  }
  if (regions.empty()) {
    throw std::invalid_argument("no sphere: the mask has no region of radius " +
                                Round1(search.min_radius_px) + " px or more");
  }
  std::sort(regions.begin(), regions.end(),
            [](const Region& a, const Region& b) { return a.area > b.area; });
  if (static_cast<int>(regions.size()) > search.max_spheres) {
    warnings->push_back(std::to_string(regions.size()) + " regions in the mask: the " +
                        std::to_string(search.max_spheres) + " largest taken as spheres");
    regions.resize(search.max_spheres);
  }
  std::vector<SphereOutline> spheres;
  for (const Region& region : regions) {
    SphereOutline s;
    // The outline at pixel edges between the region and the rest, where a pixelated disc
    // crosses half coverage: unbiased, unlike the centres of the boundary pixels.
    auto in = [&](int c, int r) { return labels.at<int>(r, c) == region.label; };
    for (int r = 0; r < mask.height; ++r) {
      for (int c = 0; c < mask.width; ++c) {
        if (!in(c, r)) continue;
        if (c > 0 && !in(c - 1, r)) s.points_px.emplace_back(c, r + 0.5);
        if (c + 1 < mask.width && !in(c + 1, r)) s.points_px.emplace_back(c + 1, r + 0.5);
        if (r > 0 && !in(c, r - 1)) s.points_px.emplace_back(c + 0.5, r);
        if (r + 1 < mask.height && !in(c, r + 1)) s.points_px.emplace_back(c + 0.5, r + 1);
      }
    }
    const cv::Rect box(stats.at<int>(region.label, cv::CC_STAT_LEFT),
                       stats.at<int>(region.label, cv::CC_STAT_TOP),
                       stats.at<int>(region.label, cv::CC_STAT_WIDTH),
                       stats.at<int>(region.label, cv::CC_STAT_HEIGHT));
    const std::string where = "the region at (" + std::to_string(box.x + box.width / 2) + ", " +
                              std::to_string(box.y + box.height / 2) + ")";
    if (s.points_px.size() < 8) {
      throw std::invalid_argument(where + " fills the image: no outline to fit a sphere to");
    }
    FitCircle(s.points_px, &s.center_x_px, &s.center_y_px, &s.radius_px, &s.fit_rms_px);
    s.visible_fraction = VisibleFraction(s, mask.width, mask.height);
    if (s.fit_rms_px > search.max_rms_ratio * s.radius_px + 0.5) {
      throw std::invalid_argument(where + " is not round (its outline lies " +
                                  Round1(s.fit_rms_px) + " px RMS from the best circle, radius " +
                                  Round1(s.radius_px) +
                                  " px): not a sphere, or the mask is off; give --circle");
    }
    if (s.visible_fraction < 0.5) {
      throw std::invalid_argument("the sphere at (" + Round1(s.center_x_px) + ", " +
                                  Round1(s.center_y_px) + ") is clipped by the image edge (" +
                                  std::to_string(int(std::round(100 * s.visible_fraction))) +
                                  "% of its outline visible): too little to fit");
    }
    if (s.visible_fraction < 0.999) {
      warnings->push_back("the sphere at (" + Round1(s.center_x_px) + ", " + Round1(s.center_y_px) +
                          ") is clipped by the image edge (" +
                          std::to_string(int(std::round(100 * s.visible_fraction))) +
                          "% of its outline visible): fitted to the visible part");
    }
    spheres.push_back(std::move(s));
  }
  return spheres;
}

std::vector<SphereOutline> FindSpheresInImages(const std::vector<const ImageF*>& images,
                                               const SphereSearch& search,
                                               std::vector<std::string>* warnings) {
  if (std::string m = search.Check(); !m.empty()) throw std::invalid_argument(m);
  if (images.empty()) throw std::invalid_argument("no images");
  const int w = images[0]->width, h = images[0]->height;
  cv::Mat mean(h, w, CV_32F, cv::Scalar(0));
  for (const ImageF* image : images) {
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        const float* v = image->at(c, r);
        float sum = 0;
        for (int k = 0; k < image->channels; ++k) sum += v[k];
        mean.at<float>(r, c) += sum / image->channels / images.size();
      }
    }
  }
  std::vector<float> values(mean.begin<float>(), mean.end<float>());
  std::nth_element(values.begin(), values.begin() + values.size() * 99 / 100, values.end());
  const float white = std::max(values[values.size() * 99 / 100], 1e-12f);
  cv::Mat tone, gray;
  cv::sqrt(cv::max(mean, 0.0f) / white, tone);
  tone.convertTo(gray, CV_8U, 255.0);
  cv::Mat smooth;
  cv::GaussianBlur(gray, smooth, cv::Size(5, 5), 1.5);
  const double size = std::min(w, h);
  std::vector<cv::Vec4f> found;  // x, y, r, votes
  cv::HoughCircles(smooth, found, cv::HOUGH_GRADIENT, 1, size / 4, 100, 30,
                   std::max<int>(search.min_radius_px, int(size / 20)), int(size / 2));
  if (found.empty()) {
    throw std::invalid_argument(
        "no sphere found in the photos (no circle in their mean); give --mask or --circle");
  }
  cv::Mat edges;
  cv::Canny(gray, edges, 50, 100);
  std::vector<SphereOutline> spheres;
  for (std::size_t i = 0; i < found.size() && int(spheres.size()) < search.max_spheres; ++i) {
    const cv::Vec4f& f = found[i];
    if (i > 0) {
      const cv::Vec4f& first = found[0];
      const bool strong = f[3] >= 0.7 * first[3];
      const bool alike = std::abs(f[2] - first[2]) <= 0.3 * first[2];
      const bool apart = std::hypot(f[0] - first[0], f[1] - first[1]) > f[2] + first[2];
      if (!strong || !alike || !apart) continue;
    }
    SphereOutline s;
    const double band = std::max(3.0, 0.05 * f[2]);
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        if (!edges.at<unsigned char>(r, c)) continue;
        const double d = std::hypot(c + 0.5 - f[0], r + 0.5 - f[1]);
        if (std::abs(d - f[2]) <= band) s.points_px.emplace_back(c + 0.5, r + 0.5);
      }
    }
    const std::string where = "the circle found at (" + Round1(f[0]) + ", " + Round1(f[1]) +
                              "), radius " + Round1(f[2]) + " px";
    if (s.points_px.size() < 3 * f[2]) {  // under half the circumference: not an outline
      throw std::invalid_argument(where +
                                  " has too few edges to be a sphere's outline; give "
                                  "--mask or --circle");
    }
    FitCircle(s.points_px, &s.center_x_px, &s.center_y_px, &s.radius_px, &s.fit_rms_px);
    // A sphere's outline shows all round (but where its stand or the image edge hides it); an
    // object's arc that happens to fit a circle covers only part of it.
    std::vector<char> bins(72, 0);
    for (const Vec2d& q : s.points_px) {
      const double a = std::atan2(q.y() - s.center_y_px, q.x() - s.center_x_px);
      bins[std::min(71, int((a + M_PI) / (2 * M_PI) * 72))] = 1;
    }
    const double coverage = std::count(bins.begin(), bins.end(), 1) / 72.0;
    if (coverage < 0.6) {
      throw std::invalid_argument(where + " shows edges over only " +
                                  std::to_string(int(std::round(100 * coverage))) +
                                  "% of its circumference: not a sphere's outline; give --mask or "
                                  "--circle");
    }
    if (s.fit_rms_px > search.max_rms_ratio * s.radius_px + 0.5) {
      throw std::invalid_argument(where + ": its edges lie " + Round1(s.fit_rms_px) +
                                  " px RMS from a circle: not a sphere; give --mask or --circle");
    }
    s.visible_fraction = VisibleFraction(s, w, h);
    warnings->push_back("no mask: found a sphere in the photos at (" + Round1(s.center_x_px) +
                        ", " + Round1(s.center_y_px) + "), radius " + Round1(s.radius_px) +
                        " px; check calibration.png, or give --mask or --circle");
    spheres.push_back(std::move(s));
  }
  return spheres;
}

SphereGeometry SphereFromOutline(const SphereOutline& outline, const Intrinsics& camera) {
  if (std::string m = camera.Check(); !m.empty()) throw std::invalid_argument(m);
  SphereGeometry g;
  g.outline = outline;
  g.camera = camera;
  if (!camera.perspective()) {
    g.center_cam = Vec3d(outline.center_x_px, -outline.center_y_px, 0);
    g.radius = outline.radius_px;
    return g;
  }
  // The rays through the outline are tangent to the sphere: they make one angle α with the
  // axis toward the centre, d·a = cos α for every ray d, linear in a / cos α.
  std::vector<Vec2d> points = outline.points_px;
  if (points.empty()) {  // a circle given by hand: its samples
    for (int i = 0; i < 360; ++i) {
      const double a = i * M_PI / 180;
      points.emplace_back(outline.center_x_px + outline.radius_px * std::cos(a),
                          outline.center_y_px + outline.radius_px * std::sin(a));
    }
  }
  Eigen::MatrixX3d rays(points.size(), 3);
  for (std::size_t i = 0; i < points.size(); ++i) {
    rays.row(i) =
        Vec3d((points[i].x() - camera.cx) / camera.fx, -(points[i].y() - camera.cy) / camera.fy, -1)
            .normalized()
            .transpose();
  }
  const Vec3d a = rays.colPivHouseholderQr().solve(Eigen::VectorXd::Ones(points.size()));
  const double cos_alpha = std::min(1.0 / a.norm(), 1 - 1e-12);
  g.center_cam = a.normalized() / std::sqrt(1 - cos_alpha * cos_alpha);
  g.radius = 1;
  return g;
}

bool SphereGeometry::At(double x_px, double y_px, Vec3d* normal_cam, Vec3d* view_cam,
                        Vec3d* point_cam) const {
  if (!camera.perspective()) {
    const double dx = x_px - center_cam.x(), dy = -y_px - center_cam.y();
    const double z2 = radius * radius - dx * dx - dy * dy;
    if (z2 < 0) return false;
    *point_cam = Vec3d(x_px, -y_px, std::sqrt(z2));
    *normal_cam = (*point_cam - center_cam) / radius;
    *view_cam = Vec3d(0, 0, 1);
    return true;
  }
  const Vec3d d =
      Vec3d((x_px - camera.cx) / camera.fx, -(y_px - camera.cy) / camera.fy, -1).normalized();
  const double b = d.dot(center_cam);
  const double disc = b * b - (center_cam.squaredNorm() - radius * radius);
  if (disc < 0) return false;
  *point_cam = (b - std::sqrt(disc)) * d;
  *normal_cam = (*point_cam - center_cam).normalized();
  *view_cam = -d;
  return true;
}

ImageF SphereNormalMap(const std::vector<SphereGeometry>& spheres, int width, int height,
                       Mask* on_sphere) {
  ImageF normals(width, height, 3, 0.f);
  *on_sphere = Mask(width, height, false);
  for (const SphereGeometry& s : spheres) {
    for (int r = 0; r < height; ++r) {
      for (int c = 0; c < width; ++c) {
        const double dx = c + 0.5 - s.outline.center_x_px, dy = r + 0.5 - s.outline.center_y_px;
        if (std::hypot(dx, dy) > s.outline.radius_px - 1) continue;
        Vec3d n, v, p;
        if (!s.At(c + 0.5, r + 0.5, &n, &v, &p)) continue;
        std::copy(n.data(), n.data() + 3, normals.at(c, r));
        on_sphere->inside[std::size_t(r) * width + c] = 1;
      }
    }
  }
  return normals;
}

Vec2d SphereGeometry::Project(const Vec3d& p) const {
  if (!camera.perspective()) return Vec2d(p.x(), -p.y());
  return Vec2d(camera.cx + camera.fx * p.x() / -p.z(), camera.cy - camera.fy * p.y() / -p.z());
}

Vec3d ClosestPoint(const Vec3d& oa, const Vec3d& da, const Vec3d& ob, const Vec3d& db,
                   double* gap) {
  // Minimize |oa + s da − ob − t db|²: a 2 × 2 system, singular for parallel rays.
  const Vec3d w = oa - ob;
  const double a = da.dot(da), b = da.dot(db), c = db.dot(db), d = da.dot(w), e = db.dot(w);
  const double den = a * c - b * b;
  if (den < 1e-12 * a * c) {
    *gap = std::numeric_limits<double>::infinity();
    return Vec3d::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  const double s = (b * e - c * d) / den, t = (a * e - b * d) / den;
  const Vec3d pa = oa + s * da, pb = ob + t * db;
  // Rays that meet behind their origins diverge: no point light lies there.
  *gap = s > 0 && t > 0 ? (pa - pb).norm() : std::numeric_limits<double>::infinity();
  return 0.5 * (pa + pb);
}

}  // namespace iphong::calibrate
