// Height maps (and perspective depth maps) as surfaces: their mesh and their normals.
//
// Pixel (col, row) of an orthographic height map is the point
//     (x, y, z) = ((col + 0.5 − W/2)·s, (H/2 − row − 0.5)·s, height)
// in the camera frame (x right, y up, z toward the viewer; s = pixel size), so the mesh is
// centred on the optical axis. A perspective depth map gives the point at `depth` along the ray
// through the pixel centre (intrinsics fx, fy, cx, cy in pixels; x right, y up, z toward the
// viewer, so z = −depth).
#pragma once

#include <string>
#include <vector>

#include "core/types.h"
#include "geometry/mesh.h"

namespace iphong::geometry {

// A scale — pixel size, focal length — in [1e-12, 1e12]: heights and points are stored in float,
// and beyond that they overflow or vanish there (a pixel size of 1e308 wrote infinite heights).
inline bool ScaleInRange(double s) { return s >= 1e-12 && s <= 1e12; }

struct HeightMapFrame {
  double pixel_size = 1.0;  // orthographic
  bool perspective = false;
  double fx = 0, fy = 0, cx = 0, cy = 0;

  // "" or what is wrong: pixel size finite and > 0; perspective: fx, fy finite and > 0 and a
  // finite principal point.
  std::string Validate() const;
};

// The camera-frame point of pixel (col, row) with height (orthographic) or depth (perspective).
Vec3d HeightMapPoint(const HeightMapFrame& frame, int width, int height, int col, int row,
                     double value);

struct HeightMeshOptions {
  const ImageF* normals = nullptr;     // 3 channels: per-vertex normals (else from the mesh)
  const ImageF* continuity = nullptr;  // 2 channels (integrate::IntegrateResult::continuity)
  double cut_below = 0.25;             // edges with less continuity are not bridged
};

// One vertex per masked pixel with a finite value, two triangles per 2×2 block of them (one when
// only three are inside), counter-clockwise seen from the viewer. The uvs address the image
// (u = (col + 0.5)/W, v = (row + 0.5)/H, v = 0 at the top), for albedo textures. `vertex_pixel`
// (optional) receives the pixel index (row·W + col) of each vertex.
TriangleMesh MeshFromHeightMap(const ImageF& height, const Mask& mask, const HeightMapFrame& frame,
                               const HeightMeshOptions& options = {},
                               std::vector<int>* vertex_pixel = nullptr);

// Normals of the height map's surface by central differences of the camera-frame points (one-
// sided at the mask boundary); 0 where a pixel has no neighbour along a direction.
ImageF NormalsFromHeightMap(const ImageF& height, const Mask& mask, const HeightMapFrame& frame);

}  // namespace iphong::geometry
