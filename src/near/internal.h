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
// A result's unit normal per pixel of data (masked order); (0, 0, 1) where it has none.
std::vector<Vec3d> NormalsPerPixel(const solve::NormalResult& r,
                                   const solve::PhotometricData& data);
// The depth (per pixel of data: distance along the axis) that integrating the result's normals
// gives, its free number from `depth`: the geometric mean under perspective, the mean otherwise.
std::vector<double> IntegratedDepth(const solve::NormalResult& r,
                                    const solve::PhotometricData& data,
                                    const geometry::HeightMapFrame& frame,
                                    const std::vector<double>& depth, double min_cos, int threads);
// The depth scaled (perspective) or shifted (orthographic) so its mean changes by `factor`.
std::vector<double> WithFactor(const std::vector<double>& depth, double factor, bool perspective);
double Mean(const std::vector<double>& v);

}  // namespace iphong::near::internal
