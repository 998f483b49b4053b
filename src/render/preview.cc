#include "render/preview.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "render/renderer.h"

namespace iphong::render {
namespace {

ImageF NormalizedTexture(const ImageF& texture) {
  ImageF out = texture;
  const float scale = AlbedoDisplayScale(texture);
  for (float& v : out.pixels) v = std::isfinite(v) ? std::max(0.0f, v * scale) : 0.0f;
  return out;
}

}  // namespace

float AlbedoDisplayScale(const ImageF& albedo) {
  std::vector<float> peaks;
  peaks.reserve(albedo.pixel_count());
  for (std::size_t p = 0; p < albedo.pixel_count(); ++p) {
    const float* v = albedo.pixels.data() + p * albedo.channels;
    float peak = v[0];
    for (int c = 1; c < std::min(albedo.channels, 3); ++c) peak = std::max(peak, v[c]);
    if (peak > 0 && std::isfinite(peak)) peaks.push_back(peak);
  }
  if (peaks.empty()) return 1.0f;
  const std::size_t k = static_cast<std::size_t>(0.99 * (peaks.size() - 1));
  std::nth_element(peaks.begin(), peaks.begin() + k, peaks.end());
  return 0.8f / peaks[k];
}

ImageF RenderPreview(const geometry::TriangleMesh& mesh, const PreviewOptions& options) {
  if (mesh.triangles.empty()) throw std::invalid_argument("nothing to preview: the mesh is empty");
  if (options.width < 16 || options.width > 8192) {
    throw std::invalid_argument("preview width must be in 16..8192");
  }
  SceneObject object;
  object.name = "preview";
  object.mesh = mesh;
  if (options.max_wall_deg < 90) {
    const double min_nz = std::cos(options.max_wall_deg * M_PI / 180);
    geometry::TriangleMesh& m = object.mesh;
    std::size_t kept = 0;
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      if (std::abs(geometry::FaceNormal(mesh, t).z()) < min_nz) continue;
      m.triangles[kept] = m.triangles[t];
      if (!m.corner_normals.empty()) {
        for (int k = 0; k < 3; ++k) m.corner_normals[3 * kept + k] = m.corner_normals[3 * t + k];
      }
      ++kept;
    }
    if (kept > 0) {  // a mesh of walls only is shown as it is
      m.triangles.resize(kept);
      if (!m.corner_normals.empty()) m.corner_normals.resize(3 * kept);
    } else {
      m = mesh;
    }
  }
  Vec3d centroid = Vec3d::Zero();
  for (const Vec3d& p : mesh.positions) centroid += p;
  centroid /= static_cast<double>(mesh.positions.size());
  const Eigen::Affine3d turn = Eigen::AngleAxisd(options.pitch_deg * M_PI / 180, Vec3d::UnitX()) *
                               Eigen::AngleAxisd(options.yaw_deg * M_PI / 180, Vec3d::UnitY()) *
                               Eigen::Translation3d(-centroid);
  geometry::TransformMesh(object.mesh, turn);

  Vec3d lo = Vec3d::Constant(INFINITY), hi = Vec3d::Constant(-INFINITY);
  for (const Vec3d& p : object.mesh.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double span_x = std::max(hi.x() - lo.x(), 1e-9), span_y = std::max(hi.y() - lo.y(), 1e-9);
  const double margin = 1.08;
  const int height = std::clamp(static_cast<int>(std::lround(options.width * span_y / span_x)),
                                options.width / 4, 2 * options.width);
  // The framing: the whole mesh fits in both directions.
  const double extent = margin * std::max(span_x, span_y * options.width / height);

  Scene scene;
  scene.camera = geometry::Camera::Orthographic(options.width, height, extent);
  scene.camera.center =
      Vec3d(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), hi.z() + (hi - lo).norm() + 1);
  scene.lighting.lights.push_back(
      reflectance::Light::Directional(Vec3d(-0.45, 0.6, 0.65), Rgb::Constant(0.85)));
  scene.lighting.lights.push_back(
      reflectance::Light::Directional(Vec3d(0.7, -0.1, 0.7), Rgb::Constant(0.25)));
  reflectance::Material& clay = object.material;
  if (options.texture) {
    clay.kd = Rgb::Ones();
    object.albedo_texture = NormalizedTexture(*options.texture);
    // The light that fills the shadows comes from the viewer and is reflected by the surface's
    // own colour: Phong's ambient ka is one constant (the texture tints only kd), so an ambient
    // term would lift every pixel by the same grey and leave the colours pale.
    scene.lighting.lights.push_back(
        reflectance::Light::Directional(Vec3d(0, 0, 1), Rgb::Constant(0.2)));
  } else {
    clay.kd = Rgb(0.78, 0.70, 0.62);
    clay.ka = clay.kd;
    scene.lighting.ambient = Rgb::Constant(0.2);
  }
  clay.ks = Rgb::Constant(0.12);
  clay.shininess = 24;
  scene.objects.push_back(std::move(object));

  RenderOptions render;
  render.two_sided = true;  // height-map meshes are open: their backs show when turned
  render.supersampling = 2;
  render.threads = options.threads;
  RenderOutput out = Render(scene, render, false);
  const float background = 0.85f;
  for (std::size_t p = 0; p < out.image.pixel_count(); ++p) {
    if (out.mask.inside[p]) continue;
    for (int c = 0; c < 3; ++c) out.image.pixels[3 * p + c] = background;
  }
  return out.image;
}

}  // namespace iphong::render
