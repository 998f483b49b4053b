// Near-light photometric stereo (SPEC.md "Near lights"). Under point lights a pixel sees each
// light from its own surface point X: L_j(X) = (S_j − X)/|S_j − X| and E_j(X) = Φ_j·(a_j·(X −
// S_j)/|X − S_j|)^μ_j/|X − S_j|², and under a perspective camera V(X) = −X/|X|
// (reflectance::LightAt, solve::PixelLights). X depends on the surface, the surface on the
// normals, the normals on X: the loop
//
//   X⁰ on a first guess of the surface: a plane facing the camera at the object's distance;
//   pass k: normals with every pixel's own L, E and V (solve/normals.h); integrated into a
//     surface (integrate/integrate.h: log depth under a perspective camera, heights under an
//     orthographic one); the one number integration leaves free — the depth's scale, or the
//     surface's distance along the axis — chosen by the images (ChooseSurfaceOffset);
//     X^{k+1} on that surface;
//   until the normals move less than tolerance_deg on average (or stop settling), or max_passes.
//
// The first passes are Woodham's (cheap, and close enough to place the surface; more while its
// normals still move), then one full solve plans the model (the held-out choice) and searches
// every pixel's hemisphere with tables per tile of pixels that see the lights alike
// (solve/light_tiles.h), and the later passes refine each pixel locally from its last normal
// (solve::RefineNormalsWithPlan): warm starts. Once the normals settle, the lobe is chosen again
// from them (warm, no search) on the settled surface, and the loop goes on if it changed.
//
// Where nothing says how far the object is (a ring of lights in the camera's plane, no distance
// given), the images do: the surfaces Woodham's normals make at distances a factor 2 apart, the
// local minima of their misfit refined, the best start run, and a second one within 25 % of its
// misfit run too (the lower final misfit wins).
//
// Units: the lights' positions, the surface points and the depth share one unit (mm for a capture
// in the near-light layout); camera frame of SPEC.md, the eye at the origin.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "geometry/height_map.h"
#include "solve/normals.h"

namespace iphong::near {

// The surface point of each of data's pixels (masked order) at `value` (depth along the axis,
// perspective; z, orthographic), through `frame` (geometry::HeightMapPoint).
std::vector<Vec3d> SurfacePoints(const solve::PhotometricData& data,
                                 const geometry::HeightMapFrame& frame,
                                 const std::vector<double>& value);

// The object's distance along the optical axis as the lights' layout says it, or 0 when it does
// not: where the LEDs' axes point (the point nearest to every axis line, when they are not
// parallel), else the centre of the sphere the lights lie on (a dome: their distances from it
// agree within 10 %). Only a start: the loop chooses the surface's distance from the images.
double GuessDistance(const std::vector<reflectance::Light>& point_lights);

struct NearOptions {
  solve::NormalOptions normals;
  // The object's distance along the optical axis, a first guess (0: GuessDistance, else the
  // distance the images fit best among a wide range).
  double distance = 0;
  // With a distance given the surface's mean distance stays within this factor of it: the
  // images refine the distance, they do not replace it. A ring of lights in the camera's plane
  // is ambiguous there: lights on a cone round the axis fit a flatter surface nearer as well
  // (docs/guides/near-lights.md). A distance from the lights' layout (the object's centre)
  // bounds it to a factor of 2.
  double distance_range = 1.25;
  int max_passes = 8;           // the full solve and the refining passes after Woodham's
  int woodham_passes = 2;       // before the full solve (more while they move); 0: straight to it
  double tolerance_deg = 0.05;  // mean change of the normals between passes that ends the loop
  double min_cos = 0.05;        // integration's grazing guard (integrate::IntegrateOptions)
  int scale_sample = 1000;      // pixels whose fits choose the surface's distance
  // Called with a line on each pass (for a command's log); may be empty.
  std::function<void(const std::string&)> log;

  std::string Validate() const;
};

struct NearPass {
  std::string kind;       // "woodham", "solve" (plan and search) or "refine"
  double change_deg = 0;  // mean angle to the last pass's normals (0 for the first)
  // How far the lights moved as the pass's new surface sees them (internal::LightsMovedDeg;
  // effective distance's passes only, else 0).
  double lights_moved_deg = 0;
  // The surface's mean distance along the axis after the pass; an effective distance's passes:
  // the D (pixels) they ran at.
  double distance = 0;
  double seconds = 0;
};

struct NearResult {
  solve::NormalResult normals;
  ImageF depth;   // 1 channel: distance along the optical axis of each pixel's point, 0 outside
  ImageF points;  // 3 channels: the surface point of each pixel (camera frame), 0 outside
  std::vector<NearPass> passes;
  bool converged = false;
  double last_change_deg = 0;
  double distance = 0;  // the surface's mean distance along the axis
  // Nothing in the options or the lights' layout gave the distance: the images chose it among
  // a wide range (a warning for the user: --distance settles it).
  bool distance_from_images = false;
  // Then, other distances whose surfaces fit the images within 25 % as well: the images leave
  // the distance ambiguous (a ring of lights round the lens under noise), --distance decides.
  std::vector<double> other_distances;
  double seconds = 0;
};

// The loop above on data whose point_lights are set (points_cam and the shared directions are
// set here). Throws std::invalid_argument for invalid data, options or frame, and when no
// distance can be found.
NearResult SolveNearLights(solve::PhotometricData data, const geometry::HeightMapFrame& frame,
                           const NearOptions& options);

// The images' misfit with the surface at `depth` (per pixel of data: distance along the axis):
// each of `sample` refits its normal from `normals` (per pixel of data) with the lights seen
// from its point, as a Lambertian surface on the observations where `fit`'s lobe is negligible
// at that normal (highlights left out, and censored above as shadows are below), and the
// censored costs in image units (solve::PixelFitter::ImageCost) are summed. Only the diffuse
// term places the surface: the lobe's per-pixel coefficient is what a pixel's few highlights
// leave uncertain, and every estimate of it moved the minimum (near.cc).
double SurfaceCost(const solve::PhotometricData& data, const geometry::HeightMapFrame& frame,
                   const std::vector<double>& depth, const std::vector<Vec3d>& normals,
                   const std::vector<std::size_t>& sample, const solve::PixelFitSettings& fit,
                   int threads);

// The surface's free number — the depth's scale (perspective) or its distance along the axis
// (orthographic) — as the images choose it: the factor on the surface's mean distance (the
// depth scaled, or shifted by the mean times factor − 1) whose SurfaceCost is lowest, over a
// grid from 1/range to range (and the mean distance within [min_distance, max_distance]) in
// steps of at most √2, then golden section to 0.05 %.
double ChooseSurfaceOffset(const solve::PhotometricData& data,
                           const geometry::HeightMapFrame& frame, const std::vector<double>& depth,
                           const std::vector<Vec3d>& normals,
                           const std::vector<std::size_t>& sample,
                           const solve::PixelFitSettings& fit, double range, int threads,
                           double min_distance = 0,
                           double max_distance = std::numeric_limits<double>::infinity());

}  // namespace iphong::near
