#include "geometry/camera.h"

#include <cmath>

namespace iphong::geometry {

Camera Camera::Orthographic(int width, int height, double extent) {
  Camera c;
  c.type = CameraType::kOrthographic;
  c.width = width;
  c.height = height;
  c.extent = extent;
  return c;
}

Camera Camera::Perspective(int width, int height, double horizontal_fov_deg, double distance) {
  Camera c;
  c.type = CameraType::kPerspective;
  c.width = width;
  c.height = height;
  c.fx = c.fy = 0.5 * width / std::tan(0.5 * horizontal_fov_deg * M_PI / 180.0);
  c.cx = 0.5 * width;
  c.cy = 0.5 * height;
  c.center = Vec3d(0, 0, distance);
  return c;
}

Vec3d Camera::Project(const Vec3d& point) const {
  const Vec3d q = rotation * (point - center);  // camera coordinates, looking down −z
  const double depth = -q.z();
  if (type == CameraType::kOrthographic) {
    const double pixel = pixel_size();
    return Vec3d((q.x() + 0.5 * extent) / pixel, (0.5 * extent * height / width - q.y()) / pixel,
                 depth);
  }
  return Vec3d(cx + fx * q.x() / depth, cy - fy * q.y() / depth, depth);
}

Vec3d Camera::Unproject(double x, double y, double depth) const {
  Vec3d q;
  if (type == CameraType::kOrthographic) {
    const double pixel = pixel_size();
    q = Vec3d(x * pixel - 0.5 * extent, 0.5 * extent * height / width - y * pixel, -depth);
  } else {
    q = Vec3d((x - cx) / fx * depth, -(y - cy) / fy * depth, -depth);
  }
  return rotation.transpose() * q + center;
}

Vec3d Camera::ViewDirection(const Vec3d& point) const {
  if (type == CameraType::kOrthographic) return view_cam();
  return (center - point).normalized();
}

std::string Camera::Validate() const {
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536) {
    return "camera size must be in 1..65536, got " + SizeText(width, height);
  }
  if (!rotation.allFinite() || !center.allFinite() ||
      !(rotation * rotation.transpose()).isIdentity(1e-9)) {
    return "camera pose must be a finite rotation and centre";
  }
  if (type == CameraType::kOrthographic) {
    if (!std::isfinite(extent) || !(extent > 0)) return "camera extent must be finite and > 0";
  } else if (!(std::isfinite(fx) && std::isfinite(fy) && fx > 0 && fy > 0 && std::isfinite(cx) &&
               std::isfinite(cy))) {
    return "perspective camera needs finite focal lengths > 0 and a finite principal point";
  }
  return "";
}

}  // namespace iphong::geometry
