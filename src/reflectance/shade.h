// The model evaluated over arrays of points: the API boundary used by the renderer's callers,
// the CLI and the Python module. Inputs are validated here (one message naming the first bad
// point); the templated core in phong.h assumes valid, unit input.
#pragma once

#include <cstddef>

#include "reflectance/lighting.h"
#include "reflectance/material.h"

namespace iphong::reflectance {

// Arrays of 3-vectors stored as count×3 row-major, camera frame.
template <typename Scalar>
struct PointsView {
  const Scalar* normals_cam = nullptr;  // count×3; normalized here, zero length is an error
  std::size_t count = 0;
  const Scalar* views_cam = nullptr;  // count×3, or one 3-vector when view_count == 1
  std::size_t view_count = 1;
  const Scalar* positions_cam = nullptr;  // count×3; required only with point lights
  const unsigned char* mask = nullptr;    // count entries, nonzero = shade; null = all
};

// Writes count×3 linear RGB values (0 where the mask is off). Evaluates in double whatever the
// storage type, splits large inputs over `threads` threads (0 = hardware concurrency).
// Throws std::invalid_argument, naming the first offending point, for a non-finite or zero-length
// normal or view, a missing position array with point lights, or an invalid material/lighting.
template <typename Scalar>
void ShadePoints(const PointsView<Scalar>& points, const Material& material,
                 const Lighting& lighting, const ModelOptions& options, Scalar* colors_out,
                 int threads = 0);

extern template void ShadePoints<float>(const PointsView<float>&, const Material&, const Lighting&,
                                        const ModelOptions&, float*, int);
extern template void ShadePoints<double>(const PointsView<double>&, const Material&,
                                         const Lighting&, const ModelOptions&, double*, int);

// Checks the options (fast_approx_log2_gamma in 0..16); empty when valid.
std::string ValidateModelOptions(const ModelOptions& options);

}  // namespace iphong::reflectance
