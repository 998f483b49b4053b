#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "integrate/integrate.h"
#include "integrate/internal.h"

namespace iphong::integrate {

IntegrateResult IntegrateNormalsCoarse(const ImageF& normals_cam, const Mask& mask,
                                       const IntegrateOptions& options, int factor) {
  if (factor <= 1) return IntegrateNormals(normals_cam, mask, options);
  if (options.perspective || options.depth_prior.pixel_count() > 0)
    throw std::invalid_argument("coarse integration: orthographic, without a depth prior");
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  // The fine map is held to IntegrateNormals' rules, so both refuse the same inputs.
  const std::size_t back_facing = internal::CheckInputs(normals_cam, mask, options);
  const int w = mask.width, h = mask.height;
  const int cw = (w + factor - 1) / factor, ch = (h + factor - 1) / factor;
  // A block joins the coarse mask if any of its pixels is masked and takes the mean of those
  // pixels' normals, so every masked pixel has a block. (DownscaleNormals, for a capture read
  // smaller, keeps only whole blocks inside instead: there no background may mix in.)
  ImageF coarse(cw, ch, 3, 0.0f);
  Mask coarse_mask(cw, ch, false);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      if (!mask.at(col, row)) continue;
      const std::size_t b = static_cast<std::size_t>(row / factor) * cw + col / factor;
      coarse_mask.inside[b] = 1;
      const float* n = normals_cam.at(col, row);
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
      n[0] = n[1] = 0, n[2] = 1;  // opposite normals cancelled: no slope to tell
    }
  }
  IntegrateOptions o = options;
  o.pixel_size = options.pixel_size * factor;
  o.allow_back_facing = true;  // the fine map passed the check; a block mean is not a new frame
  const IntegrateResult c = IntegrateNormals(coarse, coarse_mask, o);

  // Back on the fine grid: bilinear between the centres of the masked blocks (weights
  // renormalised over them), the pixel's own block where none of the four is masked.
  IntegrateResult out;
  out.summary = c.summary;
  out.summary.pixels = mask.count();
  out.summary.back_facing_pixels = back_facing;
  out.height = ImageF(w, h, 1, std::numeric_limits<float>::quiet_NaN());
  out.continuity = ImageF(w, h, 2, 1.0f);
  auto inside = [&](int ccol, int crow) {
    return ccol >= 0 && crow >= 0 && ccol < cw && crow < ch &&
           coarse_mask.inside[static_cast<std::size_t>(crow) * cw + ccol];
  };
  for (int row = 0; row < h; ++row) {
    const double v = (row + 0.5) / factor - 0.5;
    const int r0 = static_cast<int>(std::floor(v));
    const double fv = v - r0;
    for (int col = 0; col < w; ++col) {
      if (!mask.at(col, row)) continue;
      const double u = (col + 0.5) / factor - 0.5;
      const int c0 = static_cast<int>(std::floor(u));
      const double fu = u - c0;
      double sum = 0, weight = 0;
      for (int dr = 0; dr < 2; ++dr) {
        for (int dc = 0; dc < 2; ++dc) {
          if (!inside(c0 + dc, r0 + dr)) continue;
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
  // Each part's heights have mean 0 over its pixels, as IntegrateNormals' do over its cells (the
  // parts are the coarse mask's: 4-connected, as the integration's edges join them).
  cv::Mat labels;
  const int parts =
      cv::connectedComponents(cv::Mat(ch, cw, CV_8U, coarse_mask.inside.data()), labels, 4, CV_32S);
  std::vector<double> part_sum(parts, 0.0);
  std::vector<std::size_t> part_count(parts, 0);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      if (!mask.at(col, row)) continue;
      const int part = labels.at<int>(row / factor, col / factor);
      part_sum[part] += out.height.pixels[static_cast<std::size_t>(row) * w + col];
      ++part_count[part];
    }
  }
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      if (!mask.at(col, row)) continue;
      const int part = labels.at<int>(row / factor, col / factor);
      out.height.pixels[static_cast<std::size_t>(row) * w + col] -=
          static_cast<float>(part_sum[part] / static_cast<double>(part_count[part]));
    }
  }
  return out;
}

}  // namespace iphong::integrate
