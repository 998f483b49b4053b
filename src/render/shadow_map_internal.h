// Cast shadows for the renderer: the scene's depth as seen from one light (an orthographic view
// along a directional light, a perspective one from a point light), and the test of whether a
// surface point in the camera frame is lit. Implementation detail of renderer.cc; Lit is inline
// because it runs per pixel and light.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "geometry/camera.h"
#include "reflectance/lighting.h"
#include "render/rasterizer.h"
#include "render/renderer.h"

namespace iphong::render::internal {

// A rotation whose rows are camera axes with +z along `toward_viewer`.
Eigen::Matrix3d LookRotation(const Vec3d& toward_viewer);

// Depth as seen from one light; a point is lit when it is not farther than the stored depth.
class ShadowMap {
 public:
  // Rasterizes `items` (validated by Scene::Validate) from the light, framing the scene's
  // bounding sphere. Throws std::invalid_argument for a point light inside that sphere.
  ShadowMap(const reflectance::Light& light, const std::vector<RasterItem>& items,
            const Vec3d& scene_center, double scene_radius, const RenderOptions& options);

  bool Lit(const Vec3d& point, double n_dot_l) const {
    const Vec3d s = camera_.Project(point);
    // Compared in double first: a point far outside (or NaN) must not reach an int cast.
    if (!(s.x() >= 0 && s.y() >= 0 && s.x() < camera_.width && s.y() < camera_.height)) return true;
    const int col = static_cast<int>(s.x()), row = static_cast<int>(s.y());
    const float stored = depth_[static_cast<std::size_t>(row) * camera_.width + col];
    // Slope-scaled bias: a surface seen at a grazing angle spans many depths within one texel.
    const double slope = std::sqrt(std::max(0.0, 1 - n_dot_l * n_dot_l)) / std::max(n_dot_l, 0.1);
    const double texel = perspective_ ? s.z() / camera_.fx : texel_;  // footprint at that depth
    return s.z() <= stored + bias_texels_ * texel * (1 + slope);
  }

 private:
  geometry::Camera camera_;
  std::vector<float> depth_;
  double texel_ = 0;
  double bias_texels_ = 1.5;
  bool perspective_ = false;
};

}  // namespace iphong::render::internal
