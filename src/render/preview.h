// A picture of a mesh for people to look at: the mesh turned to an oblique view (so relief
// reads as relief), framed, and Phong-shaded in clay under a key light and a fill light.
#pragma once

#include "geometry/mesh.h"

namespace iphong::render {

struct PreviewOptions {
  int width = 640;        // the height follows the mesh's framed aspect ratio
  double yaw_deg = -25;   // about the camera's y axis
  double pitch_deg = 30;  // about x: tips the top away so the relief shows
  // Linear colours (e.g. the recovered albedo) looked up at the mesh's uvs, in place of the
  // clay colour, rescaled by AlbedoDisplayScale.
  const ImageF* texture = nullptr;
  // Triangles steeper than this from the view axis (a height map's silhouette walls) are left
  // out of the picture: at a silhouette each pixel's height depends on how far its centre lies
  // from the true outline, and the oblique view shows that staircase as a row of spikes
  // (docs/guides/heights-and-meshes.md: why 80°). The mesh files keep them; 90 keeps all.
  double max_wall_deg = 80;
  int threads = 0;
};

// The factor that maps the 99th percentile of an albedo image's brightest channel (over its
// non-zero pixels) to 0.8: albedo scales are arbitrary (they absorb light intensities), pictures
// and vertex colours want [0, 1].
float AlbedoDisplayScale(const ImageF& albedo);

// Linear RGB on a light grey background. Throws std::invalid_argument for an empty mesh.
ImageF RenderPreview(const geometry::TriangleMesh& mesh, const PreviewOptions& options = {});

}  // namespace iphong::render
