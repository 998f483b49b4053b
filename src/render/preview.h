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
  // clay colour; rescaled so that its 99th percentile is 0.8 (albedo scales are arbitrary).
  const ImageF* texture = nullptr;
  int threads = 0;
};

// Linear RGB on a light grey background. Throws std::invalid_argument for an empty mesh.
ImageF RenderPreview(const geometry::TriangleMesh& mesh, const PreviewOptions& options = {});

}  // namespace iphong::render
