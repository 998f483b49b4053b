// Writing an integrated surface: the height map, its mesh and a picture of it.
#pragma once

#include <string>
#include <vector>

#include "geometry/height_map.h"
#include "integrate/integrate.h"
#include "io/output_folder.h"

namespace iphong::io {

struct SurfaceFileOptions {
  const ImageF* albedo = nullptr;  // vertex colours of the mesh and the preview's colours
  bool obj = false;                // also mesh.obj
  int preview_width = 640;
  int threads = 0;
};

struct SurfaceFiles {
  std::vector<std::string> names;  // written, in order
  std::size_t vertices = 0, triangles = 0;
  // Mean and median angle between the input normals and the height map's own (re-differentiated).
  double consistency_mean_deg = 0, consistency_median_deg = 0;
  std::string report;  // integrate.json's content
};

// The mesh of a height map (geometry::MeshFromHeightMap: per-vertex normals from `normals`,
// edges with continuity below the cut not bridged) and, with an albedo, sRGB-ready vertex colours
// scaled for display (render::AlbedoDisplayScale): what mesh.ply holds. Any pointer may be null.
struct HeightMesh {
  geometry::TriangleMesh mesh;
  std::vector<Vec3f> colors;  // one per vertex, or empty
};
HeightMesh MakeHeightMesh(const ImageF& height, const Mask& mask,
                          const geometry::HeightMapFrame& frame, const ImageF* normals,
                          const ImageF* continuity, const ImageF* albedo);

// Writes into `out` under `prefix` ("" or "sub/"): height.exr (float32, 1 channel, NaN outside the
// mask: height toward the viewer, or depth for a perspective camera), mesh.ply (binary: the masked
// pixels triangulated, per-vertex normals from `normals`, colours from the albedo when given; edges
// the integration cut are not bridged), mesh.obj on request, height.png (the mesh rendered at an
// oblique view) and integrate.json (method, solver, timings, residual, consistency).
SurfaceFiles WriteSurfaceFiles(OutputFolder& out, const std::string& prefix,
                               const integrate::IntegrateResult& result, const ImageF& normals,
                               const Mask& mask, const geometry::HeightMapFrame& frame,
                               const SurfaceFileOptions& options);

// Peak memory of integrating `pixels` normals and writing their surface files (the mesh and its
// picture dominate): 600 bytes per pixel measured on a 3-megapixel sphere, 960 with the Cholesky
// solver, rounded up. For checking before the work starts.
double EstimateSurfaceBytes(std::size_t pixels, const integrate::IntegrateOptions& options);

// The frame a result was integrated in.
geometry::HeightMapFrame FrameOf(const integrate::IntegrateOptions& options);

}  // namespace iphong::io
