// The picture a user checks a light calibration with: the sphere(s) with each highlight found
// marked and numbered, beside the light directions on a hemisphere seen from the camera.
#pragma once

#include <vector>

#include "core/types.h"

namespace iphong::io {

struct CalibrationPictureInput {
  const ImageF* background = nullptr;     // linear RGB, e.g. the brightest of the images per pixel
  std::vector<Vec3d> circles;             // (cx, cy, r) per sphere, in pixels
  std::vector<std::vector<Vec2d>> marks;  // per image, the highlight centres (may be empty)
  std::vector<Vec3d> light_dir_cam;       // per image, unit (zero = not found)
};

// Linear RGB, 8-bit ready: left the image around the spheres (or the whole image without
// circles), right the hemisphere (x right, y up, the camera's axis at the centre, rings at 30°
// and 60° elevation; lights below the horizon in red). Numbers are 1-based image indices.
ImageF CalibrationPicture(const CalibrationPictureInput& input);

}  // namespace iphong::io
