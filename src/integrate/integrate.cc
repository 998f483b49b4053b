#include "integrate/integrate.h"

#include "geometry/height_map.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "core/timing.h"
#include "integrate/internal.h"

namespace iphong::integrate {

Method ParseMethod(const std::string& name) {
  for (Method m :
       {Method::kAuto, Method::kQuadratic, Method::kDct, Method::kFft, Method::kBilateral}) {
    if (name == MethodName(m)) return m;
  }
  throw std::invalid_argument("unknown integration method '" + name +
                              "' (auto, quadratic, dct, fft, bilateral)");
}

const char* MethodName(Method method) {
  switch (method) {
    case Method::kAuto:
      return "auto";
    case Method::kQuadratic:
      return "quadratic";
    case Method::kDct:
      return "dct";
    case Method::kFft:
      return "fft";
    case Method::kBilateral:
      return "bilateral";
  }
  return "?";
}

std::string IntegrateOptions::Validate() const {
  if (!(min_cos > 0 && min_cos < 1)) return "min_cos must be in (0, 1)";
  if (!(max_back_facing >= 0 && max_back_facing <= 1)) return "max_back_facing must be in [0, 1]";
  if (!geometry::ScaleInRange(pixel_size)) return "pixel size must be between 1e-12 and 1e12";
  if (perspective) {
    const Intrinsics& k = intrinsics;
    if (!(geometry::ScaleInRange(k.fx) && geometry::ScaleInRange(k.fy)) || !std::isfinite(k.cx) ||
        !std::isfinite(k.cy)) {
      return "perspective intrinsics need fx, fy between 1e-12 and 1e12 and a finite principal "
             "point";
    }
    if (!(reference_depth > 0) || !std::isfinite(reference_depth)) {
      return "reference depth must be > 0";
    }
    if (method == Method::kDct || method == Method::kFft) {
      return "the dct and fft methods are orthographic; use quadratic or bilateral";
    }
  }
  if (depth_prior.channels != 0) {
    if (depth_prior.channels != 1) return "the depth prior must have one channel";
    // Beyond 1e12 the normals' unit weights fall below the sums' precision, and the squares the
    // solvers form overflow long before double's range: 1e300 gave heights of 0 everywhere.
    if (!geometry::ScaleInRange(prior_weight)) {
      return "prior weight must be between 1e-12 and 1e12";
    }
    if (method == Method::kDct || method == Method::kFft) {
      return "a depth prior needs the quadratic or bilateral method";
    }
  }
  if (!(stiffness > 0)) return "stiffness must be > 0";
  if (max_rounds < 1) return "max_rounds must be >= 1";
  if (!(energy_tolerance >= 0)) return "energy tolerance must be >= 0";
  if (!(cg_tolerance > 0) || cg_max_iterations < 1) return "bad conjugate-gradient settings";
  return "";
}

namespace internal {

std::size_t CheckInputs(const ImageF& normals, const Mask& mask, const IntegrateOptions& options) {
  std::size_t back_facing = 0;
  std::string first_back_facing;
  if (normals.channels != 3) throw std::invalid_argument("the normal map must have 3 channels");
  if (normals.width != mask.width || normals.height != mask.height) {
    throw std::invalid_argument("mask is " + SizeText(mask.width, mask.height) +
                                " but the normal map is " +
                                SizeText(normals.width, normals.height));
  }
  if (mask.count() == 0) throw std::invalid_argument("the mask is empty");
  for (int r = 0; r < normals.height; ++r) {
    for (int c = 0; c < normals.width; ++c) {
      if (!mask.at(c, r)) continue;
      const float* n = normals.at(c, r);
      const double norm =
          std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
      auto where = [&] {
        return " at pixel (col " + std::to_string(c) + ", row " + std::to_string(r) + ")";
      };
      if (!std::isfinite(norm)) throw std::invalid_argument("non-finite normal" + where());
      if (std::abs(norm - 1) > 0.01) {
        throw std::invalid_argument("normal of length " + std::to_string(norm) + where() +
                                    " is not unit (0 outside the mask only)");
      }
      if (!(n[2] > 0) && back_facing++ == 0) {
        first_back_facing = "nz = " + std::to_string(n[2]) + where();
      }
    }
  }
  const std::size_t inside = mask.count();
  if (!options.allow_back_facing && back_facing > options.max_back_facing * inside) {
    throw std::invalid_argument(
        std::to_string(back_facing) + " of " + std::to_string(inside) + " normals (" +
        std::to_string(static_cast<int>(100.0 * back_facing / inside + 0.5)) +
        "%) face away from the camera (first: " + first_back_facing +
        "): a normal map in another frame (z into the scene?); allow back-facing normals "
        "(allow_back_facing, --allow-back-facing) to treat them as grazing");
  }
  return back_facing;
}

}  // namespace internal

GridGradients GradientsFromNormals(const ImageF& normals, const Mask& mask,
                                   const IntegrateOptions& options) {
  GridGradients g;
  g.width = normals.width;
  g.height = normals.height;
  const std::size_t size = normals.pixel_count();
  g.d_col.assign(size, 0), g.d_row.assign(size, 0), g.cos_view.assign(size, 0);
  const Intrinsics& k = options.intrinsics;
  for (int r = 0; r < g.height; ++r) {
    for (int c = 0; c < g.width; ++c) {
      if (!mask.at(c, r)) continue;
      const float* n = normals.at(c, r);
      const double nx = n[0], ny = n[1], nz = n[2];
      const std::size_t p = static_cast<std::size_t>(r) * g.width + c;
      if (!options.perspective) {
        // Clamping nz keeps the slope's direction and caps its size at √(1 − m²)/m.
        const double z = std::max(nz, options.min_cos);
        g.d_col[p] = static_cast<float>(-nx / z);
        g.d_row[p] = static_cast<float>(ny / z);  // rows run down, y up
        g.cos_view[p] = static_cast<float>(z);
        continue;
      }
      const double u = (c + 0.5 - k.cx) / k.fx, v = (r + 0.5 - k.cy) / k.fy;
      const double ray = std::sqrt(u * u + v * v + 1);
      // D = n·(ray in the x-right, y-down, z-forward frame); −D/|ray| is the cosine to the ray.
      const double d = std::min(nx * u - ny * v - nz, -options.min_cos * ray);
      g.d_col[p] = static_cast<float>(-(nx / k.fx) / d);
      g.d_row[p] = static_cast<float>((ny / k.fy) / d);
      g.cos_view[p] = static_cast<float>(-d / ray);
    }
  }
  return g;
}

std::vector<double> IntegrateProfile(const std::vector<Eigen::Vector2d>& normals_xz, double step) {
  std::vector<double> heights(normals_xz.size(), 0.0);
  auto slope = [&](std::size_t i) {
    const Eigen::Vector2d& n = normals_xz[i];
    if (!(n.y() > 0))
      throw std::invalid_argument("profile normal " + std::to_string(i) +
                                  " has Nz <= 0: the profile is not a height");
    return -n.x() / n.y();
  };
  for (std::size_t i = 1; i < normals_xz.size(); ++i) {
    heights[i] = heights[i - 1] + 0.5 * step * (slope(i - 1) + slope(i));
  }
  if (!normals_xz.empty()) slope(0);
  return heights;
}

IntegrateResult IntegrateNormals(const ImageF& normals_cam, const Mask& mask,
                                 const IntegrateOptions& options) {
  const auto start = Clock::now();
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  const std::size_t back_facing = internal::CheckInputs(normals_cam, mask, options);
  const bool has_prior = options.depth_prior.channels == 1;
  if (has_prior &&
      (options.depth_prior.width != mask.width || options.depth_prior.height != mask.height)) {
    throw std::invalid_argument("the depth prior's size differs from the normal map's");
  }

  IntegrateResult result;
  IntegrateSummary& s = result.summary;
  s.pixels = mask.count();
  s.back_facing_pixels = back_facing;
  Method method = options.method;
  if (method == Method::kAuto) {
    const bool full = s.pixels == mask.inside.size();
    method = full && !options.perspective && !has_prior ? Method::kDct : Method::kQuadratic;
  }
  s.method = method;

  const GridGradients g = GradientsFromNormals(normals_cam, mask, options);
  const int w = mask.width, h = mask.height;
  // Solution per grid pixel (the integrated unit), NaN outside the mask.
  std::vector<double> f(mask.inside.size(), std::numeric_limits<double>::quiet_NaN());
  if (method == Method::kDct || method == Method::kFft) {
    s.setup_seconds = SecondsSince(start);
    const auto solve_start = Clock::now();
    std::vector<double> full = method == Method::kDct ? internal::SolveRectangleNeumann(g)
                                                      : internal::SolveRectanglePeriodic(g);
    s.solve_seconds = SecondsSince(solve_start);
    s.solver = MethodName(method);
    s.components = 1;
    s.memory_bytes = full.size() * sizeof(double) * (method == Method::kDct ? 2 : 6);
    double sum = 0;
    for (std::size_t p = 0; p < full.size(); ++p) sum += mask.inside[p] ? full[p] : 0.0;
    const double mean = sum / s.pixels;
    for (std::size_t p = 0; p < full.size(); ++p) {
      if (mask.inside[p]) f[p] = full[p] - mean;
    }
    // Residual of the edge equations inside the mask.
    double sq = 0;
    std::size_t count = 0;
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        const std::size_t p = static_cast<std::size_t>(r) * w + c;
        if (!mask.inside[p]) continue;
        if (c + 1 < w && mask.inside[p + 1]) {
          const double e = f[p + 1] - f[p] - 0.5 * (g.d_col[p] + g.d_col[p + 1]);
          sq += e * e, ++count;
        }
        if (r + 1 < h && mask.inside[p + w]) {
          const double e = f[p + w] - f[p] - 0.5 * (g.d_row[p] + g.d_row[p + w]);
          sq += e * e, ++count;
        }
      }
    }
    s.rms_residual = count ? std::sqrt(sq / count) : 0.0;
    result.continuity = ImageF(w, h, 2, 0.0f);
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        const std::size_t p = static_cast<std::size_t>(r) * w + c;
        if (!mask.inside[p]) continue;
        float* cont = result.continuity.at(c, r);
        cont[0] = c + 1 < w && mask.inside[p + 1] ? 1.0f : 0.0f;
        cont[1] = r + 1 < h && mask.inside[p + w] ? 1.0f : 0.0f;
      }
    }
  } else {
    // The prior in the integrated unit, per masked pixel.
    std::vector<double> prior;
    prior.reserve(s.pixels);
    for (std::size_t p = 0; p < mask.inside.size(); ++p) {
      if (!mask.inside[p]) continue;
      double value = std::numeric_limits<double>::quiet_NaN();
      if (has_prior) {
        const double d = options.depth_prior.pixels[p];
        if (std::isfinite(d)) {
          if (options.perspective && !(d > 0)) {
            throw std::invalid_argument("the depth prior has a depth <= 0 at pixel (col " +
                                        std::to_string(p % w) + ", row " + std::to_string(p / w) +
                                        ")");
          }
          value = options.perspective ? std::log(d) : d / options.pixel_size;
          // Beyond 1e12 (pixels, or depth units) a float height keeps no relief: 1e30 gave a
          // surface flat at the prior's value.
          if (!(std::abs(options.perspective ? d : value) <= 1e12)) {
            char text[48];
            std::snprintf(text, sizeof text, "%g", d);
            throw std::invalid_argument(
                std::string("the depth prior holds ") + text + " at pixel (col " +
                std::to_string(p % w) + ", row " + std::to_string(p / w) + "): beyond 1e12 " +
                (options.perspective ? "" : "pixels ") +
                "no height map keeps its relief (NaN marks an unknown pixel)");
          }
        }
      }
      prior.push_back(value);
    }
    s.setup_seconds = SecondsSince(start);
    const auto solve_start = Clock::now();
    internal::SparseOutcome out =
        internal::SolveMasked(g, mask, prior, options, method == Method::kBilateral);
    s.solve_seconds = SecondsSince(solve_start);
    s.solver = out.solver;
    s.components = out.components;
    s.rounds = out.rounds;
    s.iterations = out.iterations;
    s.rms_residual = out.rms_residual;
    s.cut_edges = out.cut_edges;
    s.separated_pixels = out.separated_pixels;
    s.memory_bytes = out.memory_bytes;
    result.continuity = std::move(out.continuity);
    std::size_t i = 0;
    for (std::size_t p = 0; p < mask.inside.size(); ++p) {
      if (mask.inside[p]) f[p] = out.f[i++];
    }
    if (options.perspective && !has_prior) {
      const double shift = std::log(options.reference_depth);
      for (double& v : f) v += shift;  // parts had mean log depth 0
    }
  }

  result.height = ImageF(w, h, 1);
  for (std::size_t p = 0; p < f.size(); ++p) {
    const double v = options.perspective ? std::exp(f[p]) : f[p] * options.pixel_size;
    result.height.pixels[p] = static_cast<float>(v);  // NaN stays NaN outside the mask
  }
  s.total_seconds = SecondsSince(start);
  s.success = true;
  s.message = std::string(MethodName(method)) + " integration of " + std::to_string(s.pixels) +
              " pixels in " + std::to_string(s.components) + " part(s)";
  return result;
}

}  // namespace iphong::integrate
