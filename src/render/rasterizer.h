// Seed 001's scan-line rasterizer with a z-buffer.
//
// Every triangle edge goes into an edge table keyed by the first scan line it crosses; each scan
// line moves the edges that start there into the active edge list, drops the ones that ended,
// pairs a triangle's two active edges into a span and fills it. Attributes (depth, normal,
// uv, colour) are interpolated in two incremental stages exactly as in seed 001: along
// each edge by a constant step per scan line, then along the span by a constant step per pixel.
// Under a perspective camera the attributes are interpolated divided by depth and recovered per
// pixel, which makes them perspective-correct.
//
// Fill rule (top-left): a pixel belongs to a triangle when its centre (col + 0.5, row + 0.5) lies
// inside, or on a top or left edge. A pixel centre on an edge shared by two triangles is drawn by
// exactly one of them, so a mesh tiling the image covers every pixel once, without cracks.
//
// Output is a G-buffer of the nearest surface per pixel; shading happens in renderer.h.
#pragma once

#include <limits>
#include <vector>

#include "core/types.h"
#include "geometry/camera.h"
#include "geometry/mesh.h"

namespace iphong::render {

// One mesh to draw, with optional per-corner colours (3 per triangle, Gouraud and flat shading).
struct RasterItem {
  const geometry::TriangleMesh* mesh = nullptr;
  int object_id = 0;
  const std::vector<Vec3f>* corner_colors = nullptr;
};

struct RasterOptions {
  // Renormalize the interpolated normal at each pixel (seed 001); off shows the error of
  // interpolating unit vectors linearly.
  bool renormalize_normals = true;
  // Only the depth buffer (shadow maps).
  bool depth_only = false;
  // Count every fragment drawn per pixel, hidden or not (overdraw; watertightness checks).
  bool count_fragments = false;
  // Skip triangles seen from behind (clockwise on screen). For closed, consistently wound meshes
  // this changes nothing in the image and halves the work.
  bool cull_back_faces = false;
  // Interpolate uv coordinates (needed only for textures).
  bool interpolate_uv = true;
  int threads = 0;  // 0 = all cores
  int band_rows = 16;

  std::string Validate() const;
};

struct GBuffer {
  int width = 0;
  int height = 0;
  std::vector<float> depth;    // distance along the view axis; +inf where nothing was drawn
  std::vector<int> object_id;  // −1 where nothing was drawn
  std::vector<int> triangle;   // index within its mesh, −1 where nothing was drawn
  ImageF normal_cam;           // 3 channels
  ImageF position_cam;         // 3 channels, scene units
  ImageF uv;                   // 2 channels
  ImageF color;                // 3 channels, only when corner colours were given
  std::vector<int> fragments;  // per pixel, only with RasterOptions::count_fragments

  bool covered(std::size_t pixel) const { return object_id[pixel] >= 0; }
  // The surface point seen at a covered pixel (positions are not stored: depth determines them).
  Vec3d Position(const geometry::Camera& camera, std::size_t pixel) const {
    return camera.Unproject(pixel % width + 0.5, pixel / width + 0.5, depth[pixel]);
  }
};

// Rasterizes every item into a fresh G-buffer of the camera's size. Triangles with a vertex at or
// behind a perspective camera's eye plane are skipped (no near-plane clipping).
// Throws std::invalid_argument for an invalid camera, mesh or options.
GBuffer Rasterize(const std::vector<RasterItem>& items, const geometry::Camera& camera,
                  const RasterOptions& options);

namespace internal {
// Rasterize for meshes the caller has validated already (the renderer's Scene::Validate): a
// render rasterizes each mesh once per shadow map and again for the image, and would otherwise
// check every vertex and corner normal each time.
GBuffer RasterizeValidatedMeshes(const std::vector<RasterItem>& items,
                                 const geometry::Camera& camera, const RasterOptions& options);
}  // namespace internal

}  // namespace iphong::render
