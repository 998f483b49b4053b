#include "render/shade_normal_map.h"

#include <stdexcept>

#include "reflectance/shade.h"

namespace iphong::render {

ImageF ShadeSurfaceMap(const geometry::SurfaceMap& surface, const geometry::Camera& camera,
                       const reflectance::Material& material, const reflectance::Lighting& lighting,
                       const reflectance::ModelOptions& options) {
  const int w = surface.normal_cam.width;
  const int h = surface.normal_cam.height;
  if (surface.normal_cam.channels != 3 || surface.position_cam.channels != 3 ||
      surface.position_cam.width != w || surface.position_cam.height != h ||
      surface.mask.width != w || surface.mask.height != h) {
    throw std::invalid_argument("surface map: normals, positions and mask differ in size");
  }
  const Vec3f view = camera.view_cam().cast<float>();
  reflectance::PointsView<float> points;
  points.normals_cam = surface.normal_cam.pixels.data();
  points.count = surface.normal_cam.pixel_count();
  points.views_cam = view.data();
  points.view_count = 1;
  points.positions_cam = surface.position_cam.pixels.data();
  points.mask = surface.mask.inside.data();
  ImageF image(w, h, 3);
  reflectance::ShadePoints(points, material, lighting, options, image.pixels.data());
  return image;
}

}  // namespace iphong::render
