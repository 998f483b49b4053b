// The picture a user checks a light calibration with: the sphere(s) with each highlight found
// marked and numbered, beside the light directions on a hemisphere seen from the camera.
#pragma once

#include <string>
#include <vector>

#include "core/types.h"

namespace iphong::io {

struct CalibrationPictureInput {
  const ImageF* background = nullptr;     // linear RGB, e.g. the brightest of the images per pixel
  std::vector<Vec3d> circles;             // (cx, cy, r) per sphere, in pixels
  std::vector<std::vector<Vec2d>> marks;  // per image, the highlight centres (may be empty)
  std::vector<Vec3d> light_dir_cam;       // per image, unit (zero = not found)
  std::vector<std::string> labels;        // per image, what its marks say (empty: 1, 2, ...)
};

// The numbers the files' own names give the images, so the picture speaks as the folder does
// (UW's cat.0.tga ... cat.11.tga from 0, IMG_0013.JPG as 13): the last run of digits in each
// name's stem, leading zeros dropped. When some name has none, or two names give one number,
// 1-based positions in the list instead.
std::vector<std::string> ImageLabels(const std::vector<std::string>& file_names);

// Linear RGB, 8-bit ready: left the image around the spheres (or the whole image without
// circles), right the hemisphere (x right, y up, the camera's axis at the centre, rings at 30°
// and 60° elevation; lights below the horizon in red), each mark labelled (`labels`).
ImageF CalibrationPicture(const CalibrationPictureInput& input);

}  // namespace iphong::io
