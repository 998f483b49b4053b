// The near-light capture layout (SPEC.md "Near lights"): a dataset folder plus
//   light_positions.txt   one "x y z" per light, mm, camera frame (x right, y up, z toward the
//                         viewer, origin at the optical centre: the object has z < 0)
//   camera.json           {"fx", "fy", "cx", "cy"} in pixels (OpenCV's convention), or
//                         iphong's {"pixel_size"} (mm per pixel) for an orthographic camera
//   light_axes.txt        optional: each LED's axis (unit, the way it points)
//   light_anisotropy.txt  optional: each LED's μ (absent: 0, isotropic)
//   Depth_gt.mat          optional ground truth: variable Depth_gt, H×W, mm along the axis
// light_intensities.txt holds each light's Φ (irradiance × mm² along its axis). With
// light_directions.txt beside the positions, the two must describe the same lights: the
// directions from one point (the object's) toward the positions.
#pragma once

#include <string>
#include <vector>

#include "core/types.h"
#include "geometry/height_map.h"
#include "io/dataset_text.h"
#include "reflectance/lighting.h"

namespace iphong::io {

struct NearLightFiles {
  std::string positions_path;  // "" = not a near-light capture
  std::vector<Vec3d> positions_mm;
  std::vector<int> position_lines;  // each light's line in light_positions.txt
  std::string camera_path;
  CameraIntrinsics camera;
  std::string axes_path, anisotropy_path;  // "" = none
  std::vector<Vec3d> axes;                 // unit; empty = none
  std::vector<int> axis_lines;             // each axis's line in light_axes.txt
  std::vector<double> anisotropy;          // empty = all 0
  std::string depth_gt_path;               // "" = none

  bool present() const { return !positions_path.empty(); }
  // The camera as integration and the near-light solve take it (geometry::HeightMapPoint).
  geometry::HeightMapFrame frame() const;
};

// Reads the near-light files of `directory` for `count` lights (nothing when it holds no
// light_positions.txt). Throws std::runtime_error "FILE[:LINE]: what is wrong": a wrong count,
// a non-number, no camera.json or one without the four intrinsics, a light behind the camera
// (z > 0: another frame?), a zero axis, an anisotropy outside 0..1000 or without axes.
NearLightFiles FindNearLights(const std::string& directory, std::size_t count,
                              std::vector<std::string>* warnings);

// The point lights of the files, with their intensities Φ (RGB per light).
std::vector<reflectance::Light> NearPointLights(const NearLightFiles& files,
                                                const std::vector<Vec3d>& intensities);

// The object's distance along the optical axis (mm) as the lights' layout places it:
// near::GuessDistance, else the lights' median distance from the camera.
double LayoutDistanceMm(const NearLightFiles& files);

// Unit directions toward the lights from the object as their layout places it (the point on the
// optical axis at LayoutDistanceMm): the directions a near-light capture without
// light_directions.txt is shown and checked with.
std::vector<Vec3d> DirectionsFromPositions(const NearLightFiles& files);

// With light_directions.txt beside light_positions.txt: throws "light_directions.txt:LINE:"
// where a direction is more than 10° from the one toward its position from the point nearest to
// every light's line (positions and directions of different lights, or another frame), or when
// that point is behind the camera.
void CheckDirectionsAgree(const NearLightFiles& files, const std::vector<Vec3d>& directions,
                          const std::string& directions_path,
                          const std::vector<int>& direction_lines);

}  // namespace iphong::io
