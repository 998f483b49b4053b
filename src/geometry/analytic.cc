#include "geometry/analytic.h"

#include <cmath>
#include <stdexcept>

namespace iphong::geometry {

SurfaceMap SampleSphere(const Camera& camera, const Vec3d& center, double radius) {
  if (auto m = camera.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (camera.type != CameraType::kOrthographic || !camera.rotation.isIdentity() ||
      !camera.center.isZero()) {
    throw std::invalid_argument("SampleSphere needs the orthographic main camera");
  }
  if (!center.allFinite() || !std::isfinite(radius) || !(radius > 0)) {
    throw std::invalid_argument("sphere needs a finite centre and a radius > 0");
  }
  SurfaceMap map{ImageF(camera.width, camera.height, 3), ImageF(camera.width, camera.height, 3),
                 Mask(camera.width, camera.height, false)};
  for (int row = 0; row < camera.height; ++row) {
    for (int col = 0; col < camera.width; ++col) {
      const double dx = camera.x_of_col(col) - center.x();
      const double dy = camera.y_of_row(row) - center.y();
      const double dz2 = radius * radius - dx * dx - dy * dy;
      if (!(dz2 > 0)) continue;
      const Vec3d offset(dx, dy, std::sqrt(dz2));
      const Vec3d normal = offset / radius;
      const Vec3d position = center + offset;
      float* n = map.normal_cam.at(col, row);
      float* p = map.position_cam.at(col, row);
      for (int c = 0; c < 3; ++c) {
        n[c] = static_cast<float>(normal[c]);
        p[c] = static_cast<float>(position[c]);
      }
      map.mask.inside[static_cast<std::size_t>(row) * camera.width + col] = 1;
    }
  }
  return map;
}

}  // namespace iphong::geometry
