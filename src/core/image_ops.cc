#include "core/image_ops.h"

#include <cmath>

namespace iphong {

std::string CheckRect(const PixelRect& r, int width, int height) {
  if (r.width <= 0 || r.height <= 0) return "the crop's width and height must be > 0";
  if (r.x < 0 || r.y < 0 || static_cast<long long>(r.x) + r.width > width ||
      static_cast<long long>(r.y) + r.height > height) {
    return "the crop " + std::to_string(r.x) + "," + std::to_string(r.y) + "," +
           std::to_string(r.width) + "," + std::to_string(r.height) +
           " (x,y,w,h) reaches outside the " + SizeText(width, height) + " image";
  }
  return "";
}

void TransformedSize(int width, int height, const PixelRect* crop, int downscale, int* out_width,
                     int* out_height) {
  if (crop != nullptr && crop->width > 0) {
    width = crop->width;
    height = crop->height;
  }
  *out_width = width / downscale;
  *out_height = height / downscale;
}

ImageF CropImage(const ImageF& image, const PixelRect& r) {
  ImageF out(r.width, r.height, image.channels);
  const std::size_t row_values = static_cast<std::size_t>(r.width) * image.channels;
  for (int row = 0; row < r.height; ++row) {
    const float* from = image.at(r.x, r.y + row);
    std::copy(from, from + row_values, out.at(0, row));
  }
  return out;
}

Mask CropMask(const Mask& mask, const PixelRect& r) {
  Mask out(r.width, r.height, false);
  for (int row = 0; row < r.height; ++row)
    for (int col = 0; col < r.width; ++col)
      out.inside[static_cast<std::size_t>(row) * r.width + col] = mask.at(r.x + col, r.y + row);
  return out;
}

ImageF DownscaleImage(const ImageF& image, int factor) {
  if (factor <= 1) return image;
  ImageF out(image.width / factor, image.height / factor, image.channels);
  const double scale = 1.0 / (static_cast<double>(factor) * factor);
  std::vector<double> sum(image.channels);
  for (int row = 0; row < out.height; ++row)
    for (int col = 0; col < out.width; ++col) {
      std::fill(sum.begin(), sum.end(), 0.0);
      for (int dy = 0; dy < factor; ++dy)
        for (int dx = 0; dx < factor; ++dx) {
          const float* v = image.at(col * factor + dx, row * factor + dy);
          for (int c = 0; c < image.channels; ++c) sum[c] += v[c];
        }
      float* o = out.at(col, row);
      for (int c = 0; c < image.channels; ++c) o[c] = static_cast<float>(sum[c] * scale);
    }
  return out;
}

Mask DownscaleMask(const Mask& mask, int factor) {
  if (factor <= 1) return mask;
  Mask out(mask.width / factor, mask.height / factor, true);
  for (int row = 0; row < out.height; ++row)
    for (int col = 0; col < out.width; ++col) {
      bool all = true;
      for (int dy = 0; dy < factor && all; ++dy)
        for (int dx = 0; dx < factor && all; ++dx)
          all = mask.at(col * factor + dx, row * factor + dy);
      out.inside[static_cast<std::size_t>(row) * out.width + col] = all;
    }
  return out;
}

ImageF DownscaleNormals(const ImageF& normals, int factor) {
  if (factor <= 1) return normals;
  ImageF out(normals.width / factor, normals.height / factor, 3);
  for (int row = 0; row < out.height; ++row)
    for (int col = 0; col < out.width; ++col) {
      Vec3d sum = Vec3d::Zero();
      bool complete = true;
      for (int dy = 0; dy < factor; ++dy)
        for (int dx = 0; dx < factor; ++dx) {
          const float* n = normals.at(col * factor + dx, row * factor + dy);
          const Vec3d v(n[0], n[1], n[2]);
          complete = complete && v.squaredNorm() > 0;
          sum += v;
        }
      if (!complete || !(sum.norm() > 0)) continue;
      sum.normalize();
      float* o = out.at(col, row);
      for (int c = 0; c < 3; ++c) o[c] = static_cast<float>(sum[c]);
    }
  return out;
}

}  // namespace iphong
