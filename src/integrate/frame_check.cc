#include "integrate/frame_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "geometry/height_map.h"
#include "integrate/integrate.h"

namespace iphong::integrate {

namespace {

template <typename T>
Vec3T<T> Apply(PlaneReading reading, const Vec3T<T>& v) {
  switch (reading) {
    case PlaneReading::kAsGiven:
      return v;
    case PlaneReading::kYNegated:
      return {v.x(), -v.y(), v.z()};
    case PlaneReading::kXNegated:
      return {-v.x(), v.y(), v.z()};
    case PlaneReading::kXYNegated:
      return {-v.x(), -v.y(), v.z()};
    case PlaneReading::kSwapped:
      return {v.y(), v.x(), v.z()};
    case PlaneReading::kSwappedNegated:
      return {-v.y(), -v.x(), v.z()};
    case PlaneReading::kRotated90:
      return {-v.y(), v.x(), v.z()};
    case PlaneReading::kRotated270:
      return {v.y(), -v.x(), v.z()};
  }
  return v;
}

// The field averaged over f×f blocks (a block is kept when at least half of it is inside and
// its mean normal is not zero), normalized.
void Downsample(const ImageF& normals, const Mask& mask, int f, ImageF* out, Mask* out_mask) {
  NormalBlockAverage average(mask.width, mask.height, f);
  average.AddRows(0, normals, mask);
  average.Result(out, out_mask);
}

}  // namespace

const char* PlaneReadingName(PlaneReading reading) {
  switch (reading) {
    case PlaneReading::kAsGiven:
      return "as given";
    case PlaneReading::kYNegated:
      return "y negated";
    case PlaneReading::kXNegated:
      return "x negated";
    case PlaneReading::kXYNegated:
      return "x and y negated";
    case PlaneReading::kSwapped:
      return "x and y swapped";
    case PlaneReading::kSwappedNegated:
      return "x and y swapped and negated";
    case PlaneReading::kRotated90:
      return "x and y turned 90 degrees";
    case PlaneReading::kRotated270:
      return "x and y turned 270 degrees";
  }
  return "?";
}

Vec3f ApplyReading(PlaneReading reading, const Vec3f& v) { return Apply(reading, v); }
Vec3d ApplyReading(PlaneReading reading, const Vec3d& v) { return Apply(reading, v); }

double IntegrabilityDeg(const ImageF& normals, const Mask& mask, int threads) {
  IntegrateOptions options;
  options.method = Method::kQuadratic;
  options.allow_back_facing = true;
  options.threads = threads;
  const IntegrateResult r = IntegrateNormals(normals, mask, options);
  // The surface's own normals (a pixel per unit, orthographic): central differences, one-sided
  // where a neighbour is missing, none where a pixel has no neighbour along an axis.
  const ImageF back = geometry::NormalsFromHeightMap(r.height, mask, geometry::HeightMapFrame{});
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t p = 0; p < mask.inside.size(); ++p) {
    const float* b = back.pixels.data() + 3 * p;
    if (!mask.inside[p] || (b[0] == 0 && b[1] == 0 && b[2] == 0)) continue;
    const float* n = normals.pixels.data() + 3 * p;
    const double cos =
        std::clamp(double(b[0]) * n[0] + double(b[1]) * n[1] + double(b[2]) * n[2], -1.0, 1.0);
    sum += std::acos(cos) * 180 / M_PI;
    ++count;
  }
  return count ? sum / count : std::numeric_limits<double>::quiet_NaN();
}

std::string FrameCheckOptions::Validate() const {
  if (max_side < 8) return "max_side must be at least 8";
  if (min_silhouette_pixels < 1) return "min_silhouette_pixels must be at least 1";
  if (!(silhouette_margin > 0 && silhouette_margin <= 2)) return "silhouette_margin in (0, 2]";
  if (!(integrability_ratio >= 1) || !std::isfinite(integrability_ratio))
    return "integrability_ratio must be finite and at least 1";
  return "";
}

NormalBlockAverage::NormalBlockAverage(int width, int height, int factor)
    : width_(width), height_(height), factor_(std::max(1, factor)) {
  blocks_w_ = (width_ + factor_ - 1) / factor_;
  blocks_h_ = (height_ + factor_ - 1) / factor_;
  const std::size_t blocks = static_cast<std::size_t>(blocks_w_) * blocks_h_;
  sum_.assign(3 * blocks, 0.0);
  used_.assign(blocks, 0);
  seen_.assign(blocks, 0);
}

void NormalBlockAverage::AddRows(int y0, const ImageF& rows, const Mask& usable) {
  if (rows.width != width_ || usable.width != width_ || usable.height != rows.height ||
      rows.channels != 3 || y0 < 0 || y0 + rows.height > height_) {
    throw std::invalid_argument("block average: rows outside the field");
  }
  for (int r = 0; r < rows.height; ++r) {
    for (int c = 0; c < width_; ++c) {
      const std::size_t b = static_cast<std::size_t>((y0 + r) / factor_) * blocks_w_ + c / factor_;
      ++seen_[b];
      const std::size_t p = static_cast<std::size_t>(r) * width_ + c;
      if (!usable.inside[p]) continue;
      const float* n = rows.pixels.data() + 3 * p;
      const Vec3d v(n[0], n[1], n[2]);
      if (v.norm() == 0) continue;
      const Vec3d u = v.normalized();
      for (int k = 0; k < 3; ++k) sum_[3 * b + k] += u[k];
      ++used_[b];
    }
  }
}

void NormalBlockAverage::Result(ImageF* field, Mask* kept) const {
  *field = ImageF(blocks_w_, blocks_h_, 3, 0.0f);
  *kept = Mask(blocks_w_, blocks_h_, false);
  for (std::size_t b = 0; b < used_.size(); ++b) {
    const Vec3d sum(sum_[3 * b], sum_[3 * b + 1], sum_[3 * b + 2]);
    if (2 * used_[b] < seen_[b] || !(sum.norm() > 1e-6 * used_[b])) continue;
    const Vec3d n = sum.normalized();
    for (int k = 0; k < 3; ++k) field->pixels[3 * b + k] = static_cast<float>(n[k]);
    kept->inside[b] = 1;
  }
}

FrameCheckResult CheckNormalFrame(const ImageF& normals_cam, const Mask& mask,
                                  const FrameCheckOptions& options) {
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (normals_cam.channels != 3 || normals_cam.width != mask.width ||
      normals_cam.height != mask.height) {
    throw std::invalid_argument("the normal map's size differs from the mask's");
  }
  const int w = mask.width, h = mask.height;
  Mask usable(w, h, false);
  for (std::size_t p = 0; p < mask.inside.size(); ++p) {
    if (!mask.inside[p]) continue;
    const float* n = normals_cam.pixels.data() + 3 * p;
    if (!std::isfinite(n[0]) || !std::isfinite(n[1]) || !std::isfinite(n[2]))
      throw std::invalid_argument("a normal inside the mask is not finite");
    usable.inside[p] = n[0] != 0 || n[1] != 0 || n[2] != 0;
  }

  FrameCheckResult result;
  result.scores.resize(kPlaneReadings);
  for (int i = 0; i < kPlaneReadings; ++i) result.scores[i].reading = PlaneReading(i);

  // Silhouette: Σ over steep edge pixels of the outward step (sum of the 8-neighbour steps that
  // leave the mask inside the image), against each reading of n_xy.
  double cos_sum[kPlaneReadings] = {};
  std::size_t steep = 0;
  for (int row = 0; row < h; ++row) {
    for (int c = 0; c < w; ++c) {
      const std::size_t p = static_cast<std::size_t>(row) * w + c;
      if (!usable.inside[p]) continue;
      double ox = 0, oy = 0;
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int r2 = row + dr, c2 = c + dc;
          if ((dr == 0 && dc == 0) || r2 < 0 || c2 < 0 || r2 >= h || c2 >= w) continue;
          if (mask.inside[static_cast<std::size_t>(r2) * w + c2]) continue;
          ox += dc, oy -= dr;
        }
      }
      const double out_len = std::hypot(ox, oy);
      if (out_len == 0) continue;
      const float* n = normals_cam.pixels.data() + 3 * p;
      const Vec3d v = Vec3d(n[0], n[1], n[2]).normalized();
      const double xy = std::hypot(v.x(), v.y());
      if (xy < 0.5) continue;
      ++steep;
      for (int i = 0; i < kPlaneReadings; ++i) {
        const Vec3d t = Apply(PlaneReading(i), v);
        cos_sum[i] += (t.x() * ox + t.y() * oy) / (out_len * xy);
      }
    }
  }
  result.silhouette_pixels = steep;
  const bool silhouette = steep >= static_cast<std::size_t>(options.min_silhouette_pixels);
  for (int i = 0; i < kPlaneReadings; ++i) {
    result.scores[i].silhouette_cos =
        silhouette ? cos_sum[i] / steep : std::numeric_limits<double>::quiet_NaN();
  }

  // Integrability on a field of at most max_side a side. Readings related by a half turn share
  // their figure (the same surface upside down), so four integrations serve the eight.
  const int factor = std::max(1, (std::max(w, h) + options.max_side - 1) / options.max_side);
  ImageF small;
  Mask small_mask;
  Downsample(normals_cam, usable, factor, &small, &small_mask);
  const bool integrable = small_mask.count() >= 16;
  for (int i = 0; i < 4; ++i) {
    const PlaneReading reading = i == 0   ? PlaneReading::kAsGiven
                                 : i == 1 ? PlaneReading::kYNegated
                                 : i == 2 ? PlaneReading::kSwapped
                                          : PlaneReading::kRotated90;
    const PlaneReading half_turn = i == 0   ? PlaneReading::kXYNegated
                                   : i == 1 ? PlaneReading::kXNegated
                                   : i == 2 ? PlaneReading::kSwappedNegated
                                            : PlaneReading::kRotated270;
    double deg = std::numeric_limits<double>::quiet_NaN();
    if (integrable) {
      ImageF read = small;
      for (std::size_t p = 0; p < small_mask.inside.size(); ++p) {
        if (!small_mask.inside[p]) continue;
        float* n = read.pixels.data() + 3 * p;
        const Vec3f t = Apply(reading, Vec3f(n[0], n[1], n[2]));
        n[0] = t.x(), n[1] = t.y(), n[2] = t.z();
      }
      deg = IntegrabilityDeg(read, small_mask, options.threads);
    }
    result.scores[int(reading)].consistency_deg = deg;
    result.scores[int(half_turn)].consistency_deg = deg;
  }

  // The verdict.
  const FrameReadingScore& given = result.scores[0];
  int pick = 0;
  char why[200] = "";
  if (silhouette) {
    int best = 0;
    for (int i = 1; i < kPlaneReadings; ++i) {
      if (result.scores[i].silhouette_cos > result.scores[best].silhouette_cos) best = i;
    }
    const FrameReadingScore& b = result.scores[best];
    const bool surface_agrees =
        !integrable || b.consistency_deg <= given.consistency_deg * 1.05 + 1e-9;
    if (best != 0 && b.silhouette_cos >= options.silhouette_margin &&
        b.silhouette_cos - given.silhouette_cos >= options.silhouette_margin && surface_agrees) {
      pick = best;
      std::snprintf(why, sizeof why,
                    "its normals point out of the silhouette (mean cosine %.2f against %.2f as "
                    "given) and lie %.1f deg from a surface (%.1f as given)",
                    b.silhouette_cos, given.silhouette_cos, b.consistency_deg,
                    given.consistency_deg);
    }
  }
  if (pick == 0 && integrable) {
    int best = 0;
    for (int i = 1; i < kPlaneReadings; ++i) {
      if (result.scores[i].consistency_deg < result.scores[best].consistency_deg) best = i;
    }
    const FrameReadingScore& b = result.scores[best];
    // With a silhouette, a reading it contradicts is not taken on integrability alone.
    const bool silhouette_agrees = !silhouette || b.silhouette_cos >= given.silhouette_cos - 0.1;
    if (best != 0 && given.consistency_deg >= options.integrability_ratio * b.consistency_deg &&
        silhouette_agrees) {
      pick = best;
      std::snprintf(why, sizeof why,
                    "its normals lie %.1f deg from a surface integrated from them, against %.1f "
                    "as given",
                    b.consistency_deg, given.consistency_deg);
    }
  }
  result.better = PlaneReading(pick);
  if (pick != 0) {
    result.message = std::string("read with ") + PlaneReadingName(result.better) +
                     ", the normals fit the object better: " + why;
    if (!silhouette || std::isnan(result.scores[pick].silhouette_cos)) {
      // T and T after a half turn give the same surface upside down.
      static const int kHalfTurn[kPlaneReadings] = {3, 2, 1, 0, 5, 4, 7, 6};
      result.message += std::string(" (or ") + PlaneReadingName(PlaneReading(kHalfTurn[pick])) +
                        ": the same surface upside down, which only a silhouette tells apart)";
    }
  }
  return result;
}

}  // namespace iphong::integrate
