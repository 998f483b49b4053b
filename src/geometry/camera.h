// Cameras, in the frame of core/types.h (x right, y up, z toward the viewer; row 0 at the top,
// pixel centres at (col + 0.5, row + 0.5)).
#pragma once

#include <string>

#include "core/types.h"

namespace iphong::geometry {

// Orthographic camera looking down −z: the image spans `extent` scene units in x, centred on the
// origin, y spans extent·height/width; the view vector is (0, 0, 1) at every pixel.
struct OrthographicCamera {
  int width = 256;
  int height = 256;
  double extent = 2.0;

  double pixel_size() const { return extent / width; }
  // Scene x, y of the centre of pixel (col, row).
  double x_of_col(double col) const { return (col + 0.5) * pixel_size() - 0.5 * extent; }
  double y_of_row(double row) const {
    return 0.5 * extent * height / width - (row + 0.5) * pixel_size();
  }
  Vec3d view_cam() const { return Vec3d(0, 0, 1); }

  std::string Validate() const;
};

}  // namespace iphong::geometry
