// Conversions between Python values and iphong's types, shared by the binding files: numpy views
// of iphong's arrays (copies, C order), and numbers, triples and arrays read from Python values
// with messages that name the argument — TypeError for a value of the wrong type, ValueError for a
// wrong value; never a crash, never pybind11's "Unable to cast".
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/resources.h"
#include "core/types.h"
#include "solve/photometric_data.h"

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

// One RGB or xyz triple as a Python list of three floats.
inline py::list ToList(const Vec3d& v) { return py::cast(std::vector<double>{v[0], v[1], v[2]}); }

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

inline std::string TypeName(const py::handle& value) {
  return py::str(py::type::handle_of(value).attr("__name__"));
}

// A finite number: int, float or anything with __float__ (numpy scalars), not str or bool.
inline double ToNumber(const py::handle& value, const std::string& what) {
  if (value.is_none() || py::isinstance<py::str>(value) || py::isinstance<py::bytes>(value) ||
      py::isinstance<py::bool_>(value) || !PyNumber_Check(value.ptr())) {
    throw py::type_error(what + ": expected a number, got " + TypeName(value));
  }
  PyObject* as_float = PyNumber_Float(value.ptr());
  if (as_float == nullptr) {
    PyErr_Clear();
    throw py::type_error(what + ": expected a number, got " + TypeName(value));
  }
  const double v = PyFloat_AsDouble(as_float);
  Py_DECREF(as_float);
  if (!std::isfinite(v)) throw std::invalid_argument(what + ": expected a finite number");
  return v;
}

// Exactly `count` finite numbers (a list, tuple or array of any shape with that many values).
inline std::vector<double> ToNumbers(const py::handle& value, std::size_t count,
                                     const std::string& what) {
  const std::string expected = "expected " + std::to_string(count) + " numbers";
  if (value.is_none() || py::isinstance<py::str>(value) || py::isinstance<py::bytes>(value) ||
      py::isinstance<py::dict>(value)) {
    throw py::type_error(what + ": " + expected + ", got " + TypeName(value));
  }
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(what + ": " + expected + ", got " + TypeName(value));
  }
  if (static_cast<std::size_t>(a.size()) != count) {
    throw std::invalid_argument(what + ": " + expected + ", got " + std::to_string(a.size()));
  }
  std::vector<double> numbers(a.data(), a.data() + count);
  for (double v : numbers) {
    if (!std::isfinite(v)) throw std::invalid_argument(what + ": expected finite numbers");
  }
  return numbers;
}

inline Vec3d ToVec3(const py::handle& value, const std::string& what) {
  const std::vector<double> v = ToNumbers(value, 3, what);
  return Vec3d(v[0], v[1], v[2]);
}

// An RGB triple given as 3 numbers or one number (grey).
inline Vec3d ToRgb(const py::handle& value, const std::string& what) {
  if (PyNumber_Check(value.ptr()) && !py::isinstance<py::array>(value) &&
      !py::isinstance<py::str>(value)) {
    return Vec3d::Constant(ToNumber(value, what));
  }
  return ToVec3(value, what);
}

inline std::string ToText(const py::handle& value, const std::string& what) {
  if (!py::isinstance<py::str>(value)) {
    throw py::type_error(what + ": expected a string, got " + TypeName(value));
  }
  return value.cast<std::string>();
}

// `expected` rows of 3 numbers, (expected, 3).
inline std::vector<Vec3d> ToRows(const py::object& value, std::size_t expected, const char* what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a) PyErr_Clear();
  if (!a || a.ndim() != 2 || a.shape(1) != 3 || static_cast<std::size_t>(a.shape(0)) != expected) {
    throw std::invalid_argument(std::string(what) + " must have shape (" +
                                std::to_string(expected) + ", 3)");
  }
  std::vector<Vec3d> rows(expected);
  for (std::size_t i = 0; i < expected; ++i) rows[i] = Vec3d(a.at(i, 0), a.at(i, 1), a.at(i, 2));
  return rows;
}

// Refuses an array whose float copy (and the conversion's temporary) would not fit the memory
// limit, before the copy is made: a broadcast view of 40000 x 40000 normals was copied into
// 19 GB and the process killed by the system, instead of an error with the figure.
inline MemoryLimit CopyLimit() {
  return MemoryLimit{0, "max_memory_gb= where the call takes it, or pass a smaller array"};
}
inline void RequireCopyFits(const py::object& value, const char* what,
                            const MemoryLimit& memory = CopyLimit()) {
  const py::array view = py::array::ensure(value);
  if (!view) {
    PyErr_Clear();
    return;  // not array-like: the conversion says so
  }
  const double bytes = 2.0 * sizeof(float) * static_cast<double>(view.size());
  if (bytes <= static_cast<double>(memory.resolved())) return;
  std::string shape = "(";
  for (py::ssize_t i = 0; i < view.ndim(); ++i)
    shape += (i ? ", " : "") + std::to_string(view.shape(i));
  shape += view.ndim() == 1 ? ",)" : ")";
  throw std::invalid_argument(memory.Check(
      bytes, std::string(what) + ": copying an array of shape " + shape + " to float32"));
}

// Light intensities: None (all ones), (K,) grey lights (the same in R, G, B) or (K, 3).
inline std::vector<Vec3d> ToIntensities(const py::object& value, std::size_t k) {
  if (value.is_none()) return std::vector<Vec3d>(k, Vec3d::Ones());
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a) PyErr_Clear();
  if (a && a.ndim() == 1 && static_cast<std::size_t>(a.shape(0)) == k) {
    std::vector<Vec3d> rows(k);
    for (std::size_t i = 0; i < k; ++i) rows[i] = Vec3d::Constant(a.at(i));
    return rows;
  }
  if (!a || a.ndim() != 2 || a.shape(1) != 3 || static_cast<std::size_t>(a.shape(0)) != k) {
    throw std::invalid_argument("light_intensities must have shape (" + std::to_string(k) +
                                ", 3) or (" + std::to_string(k) + ",)");
  }
  return ToRows(value, k, "light_intensities");
}

// From numpy: a mask (None = everything) of shape (H, W), or (H, W, C) as a picture stores it
// (a pixel is inside where any channel is non-zero), and a (H, W, 3) float image.
inline Mask ToMask(const py::object& value, int width, int height) {
  if (value.is_none()) return Mask(width, height, true);
  RequireCopyFits(value, "mask");
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a) PyErr_Clear();
  const bool shape_ok = a &&
                        (a.ndim() == 2 || (a.ndim() == 3 && a.shape(2) >= 1 && a.shape(2) <= 4)) &&
                        a.shape(0) == height && a.shape(1) == width;
  if (!shape_ok) {
    throw std::invalid_argument("mask must have shape (H, W) = (" + std::to_string(height) + ", " +
                                std::to_string(width) + "), or (H, W, channels)");
  }
  const std::size_t channels = a.ndim() == 3 ? a.shape(2) : 1;
  const std::size_t colour = std::min<std::size_t>(channels, 3);  // alpha is not the object
  Mask mask(width, height, false);
  for (std::size_t p = 0; p < mask.inside.size(); ++p)
    for (std::size_t c = 0; c < colour; ++c) mask.inside[p] |= a.data()[p * channels + c] != 0;
  return mask;
}

inline ImageF ToImage(const py::object& value, const char* what,
                      const MemoryLimit& memory = CopyLimit()) {
  RequireCopyFits(value, what, memory);
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a) PyErr_Clear();
  if (!a || a.ndim() != 3 || a.shape(2) != 3) {
    throw std::invalid_argument(std::string(what) + " must have shape (H, W, 3)");
  }
  ImageF image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)), 3);
  std::memcpy(image.pixels.data(), a.data(), image.pixels.size() * sizeof(float));
  return image;
}

using FloatStack = py::array_t<float, py::array::c_style | py::array::forcecast>;

// Images (K, H, W, 3) as one float array.
inline FloatStack ToImageStack(const py::object& value) {
  RequireCopyFits(value, "images");
  FloatStack a = FloatStack::ensure(value);
  if (!a) PyErr_Clear();
  if (!a || a.ndim() != 4 || a.shape(3) != 3 || a.shape(0) < 1) {
    throw std::invalid_argument("images must have shape (K, H, W, 3)");
  }
  if (a.shape(1) < 1 || a.shape(2) < 1) {
    throw std::invalid_argument("images: shape (" + std::to_string(a.shape(0)) + ", " +
                                std::to_string(a.shape(1)) + ", " + std::to_string(a.shape(2)) +
                                ", 3) holds no pixel");
  }
  return a;
}

// K light directions (K, 3), each finite, non-zero and returned unit.
inline std::vector<Vec3d> ToDirections(const py::object& value, std::size_t k) {
  std::vector<Vec3d> dirs = ToRows(value, k, "light_directions");
  for (Vec3d& d : dirs) {
    if (!(d.norm() > 0) || !d.allFinite())
      throw std::invalid_argument("zero or non-finite light direction");
    d.normalize();
  }
  return dirs;
}

// The masked pixels of a stack under its lights, as the solvers take them.
inline solve::PhotometricData ToObservations(const FloatStack& images,
                                             const std::vector<Vec3d>& directions,
                                             const std::vector<Vec3d>& intensities,
                                             const py::object& mask) {
  const std::size_t k = images.shape(0);
  const int h = static_cast<int>(images.shape(1)), w = static_cast<int>(images.shape(2));
  std::vector<const float*> pointers;
  for (std::size_t j = 0; j < k; ++j) pointers.push_back(images.data() + j * h * w * 3);
  return solve::GatherObservations(pointers, w, h, ToMask(mask, w, h), directions, intensities);
}

// The memory limit of a call: max_memory_gb, or the default (3/4 of the machine's).
inline MemoryLimit MemoryLimitFrom(const py::object& max_memory_gb) {
  MemoryLimit limit;
  limit.knob = "max_memory_gb=";
  if (py::isinstance<py::str>(max_memory_gb)) {  // "16GB", "512MB": as Dask takes them
    if (std::string m = ParseMemorySize(max_memory_gb.cast<std::string>(), &limit.bytes);
        !m.empty())
      throw std::invalid_argument("max_memory_gb: " + m);
  } else if (!max_memory_gb.is_none()) {
    const double gb = ToNumber(max_memory_gb, "max_memory_gb");
    if (std::string m = MemorySizeFromGb(gb, &limit.bytes); !m.empty())
      throw std::invalid_argument("max_memory_gb: " + m);
  }
  return limit;
}

}  // namespace iphong::python
