// Cameras, in the frame of core/types.h (x right, y up, z toward the viewer; row 0 at the top,
// pixel centres at (col + 0.5, row + 0.5)).
//
// The scene is expressed in the camera frame of the main camera (SPEC.md). A camera may also have
// a pose (rotation and centre), which the renderer uses for shadow maps seen from the lights.
// Screen coordinates: x = column, y = row (both continuous, pixel centres at +0.5), depth =
// distance in front of the camera along its viewing axis (smaller is nearer).
#pragma once

#include <Eigen/Core>
#include <string>

#include "core/types.h"

namespace iphong::geometry {

enum class CameraType { kOrthographic, kPerspective };

struct Camera {
  CameraType type = CameraType::kOrthographic;
  int width = 256;
  int height = 256;
  // Orthographic: the image spans `extent` scene units in x (y spans extent·height/width),
  // centred on `center`; the view vector is the camera's +z axis everywhere.
  double extent = 2.0;
  // Perspective: focal lengths and principal point in pixels; the camera sits at `center`.
  double fx = 0, fy = 0, cx = 0, cy = 0;
  // Pose: rows are the camera's x, y, z axes written in the scene frame (identity for the main
  // camera); `center` is the view centre (orthographic) or the eye (perspective).
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3d center = Vec3d::Zero();

  static Camera Orthographic(int width, int height, double extent);
  // A camera on the +z axis at `distance`, looking at the origin, with a horizontal field of view.
  static Camera Perspective(int width, int height, double horizontal_fov_deg, double distance);

  double pixel_size() const { return extent / width; }  // orthographic only
  // Scene x, y of the centre of pixel (col, row) for the orthographic main camera.
  double x_of_col(double col) const { return (col + 0.5) * pixel_size() - 0.5 * extent; }
  double y_of_row(double row) const {
    return 0.5 * extent * height / width - (row + 0.5) * pixel_size();
  }

  // Scene point → (screen x, screen y, depth).
  Vec3d Project(const Vec3d& point) const;
  // The scene point seen at screen (x, y) at `depth` (the inverse of Project).
  Vec3d Unproject(double x, double y, double depth) const;
  // Unit direction from a scene point toward the viewer.
  Vec3d ViewDirection(const Vec3d& point) const;
  // Unit view direction for an orthographic camera (the same everywhere).
  Vec3d view_cam() const { return rotation.row(2).transpose(); }

  std::string Validate() const;
};

}  // namespace iphong::geometry
