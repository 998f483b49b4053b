#include "reflectance/shade.h"

#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace iphong::reflectance {
namespace {

template <typename Scalar>
Vec3d Load(const Scalar* data, std::size_t index) {
  return Vec3d(data[3 * index], data[3 * index + 1], data[3 * index + 2]);
}

void CheckDirection(const Vec3d& v, const char* what, std::size_t index) {
  if (!v.allFinite() || !(v.squaredNorm() > 1e-24)) {
    throw std::invalid_argument(std::string(what) + " " + std::to_string(index) +
                                " must be finite and non-zero, got [" + std::to_string(v[0]) +
                                ", " + std::to_string(v[1]) + ", " + std::to_string(v[2]) + "]");
  }
}

}  // namespace

std::string ValidateModelOptions(const ModelOptions& options) {
  if (options.fast_approx_log2_gamma < 0 || options.fast_approx_log2_gamma > 16) {
    return "fast_approx_log2_gamma must be in 0..16, got " +
           std::to_string(options.fast_approx_log2_gamma);
  }
  return "";
}

template <typename Scalar>
void ShadePoints(const PointsView<Scalar>& points, const Material& material,
                 const Lighting& lighting, const ModelOptions& options, Scalar* colors_out,
                 int threads) {
  CheckMaterial(material);
  if (auto m = lighting.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = ValidateModelOptions(options); !m.empty()) throw std::invalid_argument(m);
  if (points.count > 0 && (points.normals_cam == nullptr || points.views_cam == nullptr)) {
    throw std::invalid_argument("normals and views are required");
  }
  if (points.view_count != 1 && points.view_count != points.count) {
    throw std::invalid_argument("expected one view or one per normal, got " +
                                std::to_string(points.view_count) + " views for " +
                                std::to_string(points.count) + " normals");
  }
  const bool need_positions = lighting.HasPointLights();
  if (need_positions && points.positions_cam == nullptr && points.count > 0) {
    throw std::invalid_argument("point lights need surface positions");
  }
  auto shaded = [&](std::size_t i) { return points.mask == nullptr || points.mask[i] != 0; };

  // Validate everything before writing anything, so the threads below cannot fail.
  for (std::size_t i = 0; i < points.count; ++i) {
    if (!shaded(i)) continue;
    CheckDirection(Load(points.normals_cam, i), "normal", i);
    if (need_positions && !Load(points.positions_cam, i).allFinite()) {
      throw std::invalid_argument("position " + std::to_string(i) + " is not finite");
    }
  }
  for (std::size_t i = 0; i < points.view_count; ++i) {
    CheckDirection(Load(points.views_cam, i), "view", i);
  }

  auto run = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Scalar* out = colors_out + 3 * i;
      if (!shaded(i)) {
        out[0] = out[1] = out[2] = Scalar(0);
        continue;
      }
      const Vec3d normal_cam = Load(points.normals_cam, i).normalized();
      const Vec3d view_cam = Load(points.views_cam, points.view_count == 1 ? 0 : i).normalized();
      const Vec3d position_cam =
          need_positions ? Load(points.positions_cam, i) : Vec3d::Zero().eval();
      const Vec3d color = Shade(normal_cam, view_cam, position_cam, material, lighting, options);
      for (int c = 0; c < 3; ++c) out[c] = static_cast<Scalar>(color[c]);
    }
  };

  ParallelFor(0, points.count, std::size_t{1} << 15, threads, run);
}

template void ShadePoints<float>(const PointsView<float>&, const Material&, const Lighting&,
                                 const ModelOptions&, float*, int);
template void ShadePoints<double>(const PointsView<double>&, const Material&, const Lighting&,
                                  const ModelOptions&, double*, int);

}  // namespace iphong::reflectance
