// numpy views of iphong's arrays, shared by the binding files (copies, C order).
#pragma once

#include <pybind11/numpy.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/types.h"

namespace iphong::python {

namespace py = pybind11;

// (H, W, C) float32 copy of an image; (H, W) for a one-channel image.
inline py::array_t<float> ToArray(const ImageF& image) {
  std::vector<py::ssize_t> shape = {image.height, image.width};
  if (image.channels > 1) shape.push_back(image.channels);
  py::array_t<float> array(shape);
  std::memcpy(array.mutable_data(), image.pixels.data(), image.pixels.size() * sizeof(float));
  return array;
}

inline py::array_t<bool> ToArray(const Mask& mask) {
  py::array_t<bool> array({mask.height, mask.width});
  bool* out = array.mutable_data();
  for (std::size_t p = 0; p < mask.inside.size(); ++p) out[p] = mask.inside[p] != 0;
  return array;
}

inline py::array_t<double> ToArray(const std::vector<Vec3d>& rows) {
  py::array_t<double> array({static_cast<py::ssize_t>(rows.size()), py::ssize_t{3}});
  double* out = array.mutable_data();
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (int c = 0; c < 3; ++c) out[3 * i + c] = rows[i][c];
  return array;
}

inline py::array_t<float> Stack(const std::vector<ImageF>& images) {
  if (images.empty()) return py::array_t<float>(std::vector<py::ssize_t>{0, 0, 0, 3});
  const ImageF& first = images.front();
  py::array_t<float> array(
      {static_cast<py::ssize_t>(images.size()), static_cast<py::ssize_t>(first.height),
       static_cast<py::ssize_t>(first.width), static_cast<py::ssize_t>(first.channels)});
  float* out = array.mutable_data();
  for (const ImageF& image : images) {
    std::memcpy(out, image.pixels.data(), image.pixels.size() * sizeof(float));
    out += image.pixels.size();
  }
  return array;
}

// From numpy: a (H, W) boolean mask (None = everything) and a (H, W, 3) float image.
inline Mask ToMask(const py::object& value, int width, int height) {
  if (value.is_none()) return Mask(width, height, true);
  auto a = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 2 || a.shape(0) != height || a.shape(1) != width) {
    throw std::invalid_argument("mask must have shape (H, W) = (" + std::to_string(height) + ", " +
                                std::to_string(width) + ")");
  }
  Mask mask(width, height, false);
  for (std::size_t p = 0; p < mask.inside.size(); ++p) mask.inside[p] = a.data()[p];
  return mask;
}

inline ImageF ToImage(const py::object& value, const char* what) {
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 3 || a.shape(2) != 3) {
    throw std::invalid_argument(std::string(what) + " must have shape (H, W, 3)");
  }
  ImageF image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)), 3);
  std::memcpy(image.pixels.data(), a.data(), image.pixels.size() * sizeof(float));
  return image;
}

}  // namespace iphong::python
