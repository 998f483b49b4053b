// Analytic surfaces sampled per pixel: exact normals, positions and masks, the ground truth that
// tessellated renders and the inverse solvers are checked against.
#pragma once

#include "core/types.h"
#include "geometry/camera.h"

namespace iphong::geometry {

// Per-pixel surface samples seen by a camera (a G-buffer): unit normals and positions in the
// camera frame (3 channels each), and the mask of pixels that see the surface.
struct SurfaceMap {
  ImageF normal_cam;
  ImageF position_cam;
  Mask mask;
};

// The front half of a sphere seen by an orthographic camera, sampled at pixel centres.
// Throws std::invalid_argument for an invalid camera or a non-positive radius.
SurfaceMap SampleSphere(const Camera& camera, const Vec3d& center, double radius);

}  // namespace iphong::geometry
