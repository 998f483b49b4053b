// Shared vocabulary of iphong.
//
// Frame (everywhere, see SPEC.md): the camera frame is right-handed, x to the right of the image,
// y UP, z toward the viewer. Directions are unit vectors: a light direction points from the
// surface toward the light, a view direction from the surface toward the viewer.
// Pixels: row 0 is the top image row; pixel (col, row) has its centre at (col + 0.5, row + 0.5).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

namespace iphong {

template <typename T>
using Vec3T = Eigen::Matrix<T, 3, 1>;
using Vec3d = Vec3T<double>;
using Vec3f = Vec3T<float>;
using Rgb = Vec3d;  // linear, unclamped RGB triple
using Vec2d = Eigen::Vector2d;

// A float image: `channels` interleaved values per pixel, rows stored from the top row down.
struct ImageF {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;

  ImageF() = default;
  ImageF(int w, int h, int c, float fill = 0.0f)
      : width(w), height(h), channels(c), pixels(static_cast<std::size_t>(w) * h * c, fill) {}

  std::size_t pixel_count() const { return static_cast<std::size_t>(width) * height; }
  float* at(int col, int row) {
    return pixels.data() + (static_cast<std::size_t>(row) * width + col) * channels;
  }
  const float* at(int col, int row) const {
    return pixels.data() + (static_cast<std::size_t>(row) * width + col) * channels;
  }
};

// Object mask: nonzero = object. Same layout as ImageF with one channel.
struct Mask {
  int width = 0;
  int height = 0;
  std::vector<unsigned char> inside;

  Mask() = default;
  Mask(int w, int h, bool fill)
      : width(w), height(h), inside(static_cast<std::size_t>(w) * h, fill) {}
  bool at(int col, int row) const {
    return inside[static_cast<std::size_t>(row) * width + col] != 0;
  }
  std::size_t count() const;
};

inline std::size_t Mask::count() const {
  std::size_t n = 0;
  for (unsigned char v : inside) n += v != 0;
  return n;
}

// "612x512", as messages print image sizes.
inline std::string SizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// The pixels where some channel of `image` is non-zero (normal maps store 0 outside the object),
// within `within` when given (same size).
inline Mask NonZeroPixels(const ImageF& image, const Mask* within = nullptr) {
  Mask mask(image.width, image.height, false);
  for (std::size_t p = 0; p < image.pixel_count(); ++p) {
    if (within && !within->inside[p]) continue;
    const float* v = image.pixels.data() + p * image.channels;
    for (int c = 0; c < image.channels; ++c) mask.inside[p] |= v[c] != 0;
  }
  return mask;
}

}  // namespace iphong
