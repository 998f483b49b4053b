#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "integrate/integrate.h"

namespace iphong::integrate {

IntegrateResult IntegrateNormalsCoarse(const ImageF& normals_cam, const Mask& mask,
                                       const IntegrateOptions& options, int factor) {
  if (factor <= 1) return IntegrateNormals(normals_cam, mask, options);
  if (options.perspective || options.depth_prior.pixel_count() > 0)
    throw std::invalid_argument("coarse integration: orthographic, without a depth prior");
  if (normals_cam.channels != 3 || normals_cam.width != mask.width ||
      normals_cam.height != mask.height)
    throw std::invalid_argument("coarse integration: normals and mask differ in size");
  const int w = mask.width, h = mask.height;
  const int cw = (w + factor - 1) / factor, ch = (h + factor - 1) / factor;
  // A block joins the coarse mask if any of its pixels is masked; its normal is the mean of
  // those pixels' usable normals, so a block on a silhouette sees only the object.
  ImageF coarse(cw, ch, 3, 0.0f);
  Mask coarse_mask(cw, ch, false);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      if (!mask.at(col, row)) continue;
      const std::size_t b = static_cast<std::size_t>(row / factor) * cw + col / factor;
      coarse_mask.inside[b] = 1;
      const float* n = normals_cam.pixels.data() + 3 * (static_cast<std::size_t>(row) * w + col);
      if (!(std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]))) continue;
      for (int k = 0; k < 3; ++k) coarse.pixels[3 * b + k] += n[k];
    }
  }
  for (std::size_t b = 0; b < coarse_mask.inside.size(); ++b) {
    if (!coarse_mask.inside[b]) continue;
    float* n = coarse.pixels.data() + 3 * b;
    const double norm = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    if (norm > 1e-6) {
      for (int k = 0; k < 3; ++k) n[k] = static_cast<float>(n[k] / norm);
    } else {
      n[0] = n[1] = 0, n[2] = 1;  // no usable normal in the block (flagged pixels): flat
    }
  }
  IntegrateOptions o = options;
  o.pixel_size = options.pixel_size * factor;
  IntegrateResult c = IntegrateNormals(coarse, coarse_mask, o);

  // Back on the fine grid: bilinear between the centres of the coarse cells the mask holds
  // (weights renormalised over them), the pixel's own block where none of the four is usable.
  IntegrateResult out;
  out.summary = c.summary;
  out.summary.pixels = 0;
  out.height = ImageF(w, h, 1, std::numeric_limits<float>::quiet_NaN());
  out.continuity = ImageF(w, h, 2, 1.0f);
  auto usable = [&](int ccol, int crow) {
    if (ccol < 0 || crow < 0 || ccol >= cw || crow >= ch) return false;
    const std::size_t b = static_cast<std::size_t>(crow) * cw + ccol;
    return coarse_mask.inside[b] && std::isfinite(c.height.pixels[b]);
  };
  for (int row = 0; row < h; ++row) {
    const double v = (row + 0.5) / factor - 0.5;
    const int r0 = static_cast<int>(std::floor(v));
    const double fv = v - r0;
    for (int col = 0; col < w; ++col) {
      if (!mask.at(col, row)) continue;
      ++out.summary.pixels;
      const double u = (col + 0.5) / factor - 0.5;
      const int c0 = static_cast<int>(std::floor(u));
      const double fu = u - c0;
      double sum = 0, weight = 0;
      for (int dr = 0; dr < 2; ++dr) {
        for (int dc = 0; dc < 2; ++dc) {
          if (!usable(c0 + dc, r0 + dr)) continue;
          const double wt = (dc ? fu : 1 - fu) * (dr ? fv : 1 - fv);
          sum += wt * c.height.pixels[static_cast<std::size_t>(r0 + dr) * cw + c0 + dc];
          weight += wt;
        }
      }
      const std::size_t b = static_cast<std::size_t>(row / factor) * cw + col / factor;
      out.height.pixels[static_cast<std::size_t>(row) * w + col] =
          weight > 1e-9 ? static_cast<float>(sum / weight) : c.height.pixels[b];
    }
  }
  return out;
}

}  // namespace iphong::integrate
