#include "render/shadow_map_internal.h"

#include <stdexcept>

namespace iphong::render::internal {

Eigen::Matrix3d LookRotation(const Vec3d& toward_viewer) {
  const Vec3d z = toward_viewer.normalized();
  const Vec3d up = std::abs(z.y()) < 0.9 ? Vec3d(0, 1, 0) : Vec3d(1, 0, 0);
  const Vec3d x = up.cross(z).normalized();
  const Vec3d y = z.cross(x);
  Eigen::Matrix3d r;
  r.row(0) = x.transpose();
  r.row(1) = y.transpose();
  r.row(2) = z.transpose();
  return r;
}

ShadowMap::ShadowMap(const reflectance::Light& light, const std::vector<RasterItem>& items,
                     const Vec3d& scene_center, double scene_radius, const RenderOptions& options) {
  const int size = options.shadow_map_size;
  if (light.type == reflectance::LightType::kDirectional) {
    camera_ = geometry::Camera::Orthographic(size, size, 2.1 * scene_radius);
    camera_.rotation = LookRotation(light.direction_cam);
    camera_.center = scene_center;
    texel_ = camera_.pixel_size();
  } else {
    const Vec3d offset = light.position_cam - scene_center;
    const double distance = offset.norm();
    if (!(distance > 1.05 * scene_radius)) {
      throw std::invalid_argument(
          "shadows need every point light outside the scene's bounding sphere");
    }
    const double half_angle = std::asin(scene_radius / distance) * 1.05;
    camera_.type = geometry::CameraType::kPerspective;
    camera_.width = camera_.height = size;
    camera_.fx = camera_.fy = 0.5 * size / std::tan(half_angle);
    camera_.cx = camera_.cy = 0.5 * size;
    camera_.rotation = LookRotation(offset);
    camera_.center = light.position_cam;
    perspective_ = true;
  }
  RasterOptions raster;
  raster.depth_only = true;
  raster.threads = options.threads;
  depth_ = RasterizeValidatedMeshes(items, camera_, raster).depth;
  bias_texels_ = options.shadow_bias_texels;
}

}  // namespace iphong::render::internal
