// Pieces the near-light loop (near.cc) and the effective distance (effective_distance.cc) share;
// not part of the public interface.
#pragma once

#include <vector>

#include "geometry/height_map.h"
#include "solve/normals.h"

namespace iphong::near::internal {

// A point's distance along the optical axis (−z).
double DepthOf(const Vec3d& point);
// Mean angle in degrees between two results' normals over the pixels both solved.
double MeanChangeDeg(const solve::NormalResult& a, const solve::NormalResult& b,
                     const solve::PhotometricData& data);
// How far the point lights of `data` moved as seen from each pixel when its point goes from
// data.points_cam to `points` (as many; std::invalid_argument otherwise): the larger over the
// lights of the angle between the two directions toward it plus |ln| of the ratio of its two
// irradiances (radians; π/2 where a light goes dark or lit), the mean over (up to 2000 of) the
// pixels, in degrees; 0 without point lights. A pixel's fit moves its normal by about as much as
// its lights move (all of them turned by an angle turn it by that angle).
double LightsMovedDeg(const solve::PhotometricData& data, const std::vector<Vec3d>& points);
// The same measure between two sets of point lights, each seen from its own points (as many
// lights and points in both; std::invalid_argument otherwise): how far a new D and centre move
// the lights as the pixels see them. 0 without point lights.
double LightsChangedDeg(const solve::PhotometricData& a, const solve::PhotometricData& b);
// A result's unit normal per pixel of data (masked order); (0, 0, 1) where it has none.
std::vector<Vec3d> NormalsPerPixel(const solve::NormalResult& r,
                                   const solve::PhotometricData& data);
// The depth (per pixel of data: distance along the axis) that integrating the result's normals
// gives, its free number from `depth`: the geometric mean under perspective, the mean otherwise.
// With `max_pixels` > 0 (orthographic only) a mask of more pixels is integrated on blocks of 2, 4,
// ... pixels a side, the fewest that bring it to max_pixels (integrate::IntegrateNormalsCoarse).
std::vector<double> IntegratedDepth(const solve::NormalResult& r,
                                    const solve::PhotometricData& data,
                                    const geometry::HeightMapFrame& frame,
                                    const std::vector<double>& depth, double min_cos, int threads,
                                    std::size_t max_pixels = 0);
// The distance choice's surface places the pixels to move the lights they see: at 2^18 pixels it
// is still some 512 blocks across the object, so a block is a 500th of the object, where the
// candidate distances start at about an object size.
constexpr std::size_t kChoiceSurfacePixels = std::size_t{1} << 18;
// The depth scaled (perspective) or shifted (orthographic) so its mean changes by `factor`.
std::vector<double> WithFactor(const std::vector<double>& depth, double factor, bool perspective);
double Mean(const std::vector<double>& v);

}  // namespace iphong::near::internal
