#include "io/surface.h"
#include "core/version.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "io/files.h"
#include "io/image_io.h"
#include "io/mesh_io.h"
#include "render/preview.h"
#include "solve/metrics.h"

namespace iphong::io {

double EstimateSurfaceBytes(std::size_t pixels, const integrate::IntegrateOptions& options) {
  const bool cholesky = options.solver == integrate::LinearSolver::kCholesky;
  return static_cast<double>(pixels) * (cholesky ? 1100.0 : 700.0);
}

geometry::HeightMapFrame FrameOf(const integrate::IntegrateOptions& options) {
  geometry::HeightMapFrame frame;
  frame.pixel_size = options.pixel_size;
  frame.perspective = options.perspective;
  frame.fx = options.intrinsics.fx, frame.fy = options.intrinsics.fy;
  frame.cx = options.intrinsics.cx, frame.cy = options.intrinsics.cy;
  return frame;
}

HeightMesh MakeHeightMesh(const ImageF& height, const Mask& mask,
                          const geometry::HeightMapFrame& frame, const ImageF* normals,
                          const ImageF* continuity, const ImageF* albedo) {
  geometry::HeightMeshOptions mesh_options;
  mesh_options.normals = normals;
  mesh_options.continuity = continuity;
  std::vector<int> vertex_pixel;
  HeightMesh out;
  out.mesh = geometry::MeshFromHeightMap(height, mask, frame, mesh_options, &vertex_pixel);
  if (albedo) {
    const float scale = render::AlbedoDisplayScale(*albedo);
    for (int p : vertex_pixel) {
      const float* a = albedo->at(p % albedo->width, p / albedo->width);
      const int last = albedo->channels - 1;
      out.colors.emplace_back(scale * a[0], scale * a[std::min(1, last)],
                              scale * a[std::min(2, last)]);
    }
  }
  return out;
}

SurfaceFiles WriteSurfaceFiles(OutputFolder& out, const std::string& prefix,
                               const integrate::IntegrateResult& result, const ImageF& normals,
                               const Mask& mask, const geometry::HeightMapFrame& frame,
                               const SurfaceFileOptions& options) {
  SurfaceFiles files;
  auto file = [&](const std::string& name) { return out.file(prefix + name); };
  WriteImage(file("height.exr"), result.height);
  files.names.push_back("height.exr");

  const HeightMesh built =
      MakeHeightMesh(result.height, mask, frame, &normals, &result.continuity, options.albedo);
  const geometry::TriangleMesh& mesh = built.mesh;
  const std::vector<Vec3f>& colors = built.colors;
  files.vertices = mesh.positions.size();
  files.triangles = mesh.triangles.size();
  SaveMesh(file("mesh.ply"), mesh, options.albedo ? &colors : nullptr);
  files.names.push_back("mesh.ply");
  if (options.obj) {
    SaveMesh(file("mesh.obj"), mesh, options.albedo ? &colors : nullptr);
    files.names.push_back("mesh.obj");
  }
  if (!mesh.triangles.empty()) {
    render::PreviewOptions preview;
    preview.width = options.preview_width;
    preview.texture = options.albedo;
    preview.threads = options.threads;
    WriteImage(file("height.png"), render::RenderPreview(mesh, preview));
    files.names.push_back("height.png");
  }

  const ImageF back = geometry::NormalsFromHeightMap(result.height, mask, frame);
  const Mask compared = NonZeroPixels(back, &mask);  // pixels with a neighbour each way
  if (compared.count() > 0) {
    const solve::AngularErrorMetrics m = solve::CompareNormals(back, normals, compared);
    files.consistency_mean_deg = m.mean_deg;
    files.consistency_median_deg = m.median_deg;
  }

  const integrate::IntegrateSummary& s = result.summary;
  double lo = INFINITY, hi = -INFINITY;
  for (float v : result.height.pixels) {
    if (std::isfinite(v)) lo = std::min<double>(lo, v), hi = std::max<double>(hi, v);
  }
  nlohmann::json report = {
      {"iphong_version", kVersion},
      {"method", integrate::MethodName(s.method)},
      {"solver", s.solver},
      {"pixels", s.pixels},
      {"components", s.components},
      {"rounds", s.rounds},
      {"iterations", s.iterations},
      {"setup_seconds", s.setup_seconds},
      {"solve_seconds", s.solve_seconds},
      {"total_seconds", s.total_seconds},
      {"memory_bytes", s.memory_bytes},
      {"rms_residual", s.rms_residual},
      {"cut_edges", s.cut_edges},
      {"separated_pixels", s.separated_pixels},
      {"back_facing_pixels", s.back_facing_pixels},  // nz <= 0, taken as grazing
      {"camera", frame.perspective ? "perspective" : "orthographic"},
      {"height_unit", frame.perspective ? "depth along the optical axis"
                                        : "pixels x pixel_size, toward the viewer"},
      {"pixel_size", frame.pixel_size},
      {"height_min", lo},
      {"height_max", hi},
      {"outside_mask", "NaN"},
      {"mesh_vertices", files.vertices},
      {"mesh_triangles", files.triangles},
      {"consistency_mean_deg", files.consistency_mean_deg},
      {"consistency_median_deg", files.consistency_median_deg}};
  files.report = report.dump(2);
  WriteTextFile(file("integrate.json"), files.report + "\n");
  files.names.push_back("integrate.json");
  return files;
}

}  // namespace iphong::io
