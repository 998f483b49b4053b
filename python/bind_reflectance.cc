// Python view of src/reflectance: materials, lights and the vectorized model.
// std::invalid_argument becomes ValueError (pybind11's standard translation).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <optional>
#include <sstream>
#include <stdexcept>

#include "arrays.h"
#include "bindings.h"
#include "reflectance/lighting.h"
#include "reflectance/material.h"
#include "reflectance/shade.h"

namespace py = pybind11;

namespace iphong::python {
namespace {

using reflectance::Light;
using reflectance::Lighting;
using reflectance::Material;

std::string Repr(const Vec3d& v) {
  std::ostringstream out;
  out << "[" << v[0] << ", " << v[1] << ", " << v[2] << "]";
  return out.str();
}

reflectance::ModelOptions MakeOptions(const std::string& model, bool fast_specular) {
  reflectance::ModelOptions options;
  options.lobe = reflectance::ParseLobe(model);
  options.power =
      fast_specular ? reflectance::PowerMode::kFastApprox : reflectance::PowerMode::kExact;
  return options;
}

// Shades arrays of any leading shape (..., 3); Scalar is the storage type of `normal`.
template <typename Scalar>
py::array ShadeArrays(const py::array& normal_in, const py::object& view_in,
                      const py::object& position_in, const py::object& mask_in,
                      const Material& material, const Lighting& lighting,
                      const reflectance::ModelOptions& options) {
  using Array = py::array_t<Scalar, py::array::c_style | py::array::forcecast>;
  Array normal = Array::ensure(normal_in);
  if (!normal || normal.ndim() < 1 || normal.shape(normal.ndim() - 1) != 3) {
    throw std::invalid_argument("normal must have shape (3,) or (..., 3)");
  }
  const std::vector<py::ssize_t> shape(normal.shape(), normal.shape() + normal.ndim());
  const std::size_t count = static_cast<std::size_t>(normal.size() / 3);

  Array view = Array::ensure(view_in);
  if (!view || (view.size() != 3 && view.size() != normal.size())) {
    throw std::invalid_argument("view must be one 3-vector or have the shape of normal");
  }
  // A default-constructed py::array_t is an empty array, not "none": keep absence explicit.
  std::optional<Array> position;
  if (!position_in.is_none()) {
    position = Array::ensure(position_in);
    if (!*position || position->size() != normal.size()) {
      throw std::invalid_argument("position must have the shape of normal");
    }
  }
  using MaskArray = py::array_t<unsigned char, py::array::c_style | py::array::forcecast>;
  std::optional<MaskArray> mask;
  if (!mask_in.is_none()) {
    mask = MaskArray::ensure(
        py::module_::import("numpy").attr("asarray")(mask_in).attr("astype")("uint8"));
    if (!*mask || static_cast<std::size_t>(mask->size()) != count) {
      throw std::invalid_argument("mask must have the shape of normal without its last axis");
    }
  }

  py::array_t<Scalar> out(shape);
  reflectance::PointsView<Scalar> points;
  points.normals_cam = normal.data();
  points.count = count;
  points.views_cam = view.data();
  points.view_count = view.size() == 3 ? 1 : count;
  points.positions_cam = position ? position->data() : nullptr;
  points.mask = mask ? mask->data() : nullptr;
  Scalar* out_data = out.mutable_data();
  {
    py::gil_scoped_release release;
    reflectance::ShadePoints(points, material, lighting, options, out_data);
  }
  return std::move(out);
}

}  // namespace

void BindReflectance(py::module_& m) {
  py::class_<Material>(m, "Material", "Phong material: ka, kd, ks (RGB) and shininess n.")
      .def(py::init([](const py::object& ka, const py::object& kd, const py::object& ks,
                       const py::object& shininess) {
             Material material;
             material.ka = ToRgb(ka, "ka");
             material.kd = ToRgb(kd, "kd");
             material.ks = ToRgb(ks, "ks");
             material.shininess = ToNumber(shininess, "shininess");
             reflectance::CheckMaterial(material);
             return material;
           }),
           py::arg("ka") = 0.0, py::arg("kd") = 0.0, py::arg("ks") = 0.0,
           py::arg("shininess") = 1.0)
      .def_readwrite("ka", &Material::ka)
      .def_readwrite("kd", &Material::kd)
      .def_readwrite("ks", &Material::ks)
      .def_readwrite("shininess", &Material::shininess)
      .def("__repr__", [](const Material& mat) {
        std::ostringstream out;
        out << "Material(ka=" << Repr(mat.ka) << ", kd=" << Repr(mat.kd) << ", ks=" << Repr(mat.ks)
            << ", shininess=" << mat.shininess << ")";
        return out.str();
      });

  py::enum_<reflectance::LightType>(m, "LightType")
      .value("DIRECTIONAL", reflectance::LightType::kDirectional)
      .value("POINT", reflectance::LightType::kPoint);

  py::class_<Light>(m, "Light", "A directional or point light (use DirectionalLight/PointLight).")
      .def_readonly("type", &Light::type)
      .def_readonly("direction", &Light::direction_cam)
      .def_readonly("position", &Light::position_cam)
      .def_readonly("diffuse_intensity", &Light::diffuse_intensity)
      .def_readonly("specular_intensity", &Light::specular_intensity)
      .def_readonly("falloff", &Light::inverse_square_falloff)
      .def("__repr__", [](const Light& l) {
        std::ostringstream out;
        if (l.type == reflectance::LightType::kDirectional) {
          out << "DirectionalLight(direction=" << Repr(l.direction_cam);
        } else {
          out << "PointLight(position=" << Repr(l.position_cam);
        }
        out << ", intensity=" << Repr(l.diffuse_intensity);
        if (l.specular_intensity != l.diffuse_intensity) {
          out << ", specular_intensity=" << Repr(l.specular_intensity);
        }
        if (l.type == reflectance::LightType::kPoint) {
          out << ", falloff=" << (l.inverse_square_falloff ? "True" : "False");
        }
        out << ")";
        return out.str();
      });

  m.def(
      "DirectionalLight",
      [](const py::object& direction, const py::object& intensity,
         const py::object& specular_intensity) {
        const Rgb id = ToRgb(intensity, "intensity");
        const Rgb is =
            specular_intensity.is_none() ? id : ToRgb(specular_intensity, "specular_intensity");
        return Light::Directional(ToVec3(direction, "direction"), id, is);
      },
      py::arg("direction"), py::arg("intensity") = 1.0, py::arg("specular_intensity") = py::none(),
      "A light at infinity. direction points from the surface toward the light (normalized).");

  m.def(
      "PointLight",
      [](const py::object& position, const py::object& intensity,
         const py::object& specular_intensity, bool falloff) {
        const Rgb id = ToRgb(intensity, "intensity");
        const Rgb is =
            specular_intensity.is_none() ? id : ToRgb(specular_intensity, "specular_intensity");
        return Light::Point(ToVec3(position, "position"), id, is, falloff);
      },
      py::arg("position"), py::arg("intensity") = 1.0, py::arg("specular_intensity") = py::none(),
      py::arg("falloff") = true,
      "A light at a position in the camera frame; with falloff its intensity falls as 1/d^2.");

  m.def(
      "shade",
      [](const py::object& normal, const py::object& view, const Material& material,
         const std::vector<Light>& lights, const py::object& ambient, const py::object& position,
         const py::object& mask, const std::string& model, bool fast_specular) -> py::object {
        Lighting lighting;
        lighting.ambient = ToRgb(ambient, "ambient");
        lighting.lights = lights;
        const auto options = MakeOptions(model, fast_specular);
        py::array normal_array = py::array::ensure(normal);
        if (!normal_array) throw std::invalid_argument("normal must be array-like");
        if (normal_array.dtype().is(py::dtype::of<float>())) {
          return ShadeArrays<float>(normal_array, view, position, mask, material, lighting,
                                    options);
        }
        return ShadeArrays<double>(normal_array, view, position, mask, material, lighting, options);
      },
      py::arg("normal"), py::arg("view") = py::make_tuple(0.0, 0.0, 1.0), py::arg("material"),
      py::arg("lights"), py::arg("ambient") = 0.0, py::kw_only(), py::arg("position") = py::none(),
      py::arg("mask") = py::none(), py::arg("model") = "phong", py::arg("fast_specular") = false,
      R"doc(Evaluate the reflection model.

normal: (3,) or (..., 3) surface normals in the camera frame (x right, y up, z toward the
viewer); normalized here, zero length is an error unless masked out.
view: (3,) or the shape of normal; direction from the surface toward the viewer.
lights: list of DirectionalLight / PointLight; ambient: RGB triple or number (Ia).
position: surface points (shape of normal), needed for point lights.
mask: boolean array of normal.shape[:-1]; pixels outside are 0.
model: "phong", "blinn-phong", "lambert", "oren-nayar" (rough diffuse, the facets' slope in
radians as the shininess) or "normal-centred" ((N.L)^n); fast_specular: seed 003's (1 - beta*lambda)^gamma.
Returns linear, unclamped RGB with the shape of normal (float32 for float32 input, else float64).)doc");

  py::class_<reflectance::MaterialPreset>(m, "MaterialPreset")
      .def_readonly("name", &reflectance::MaterialPreset::name)
      .def_readonly("material", &reflectance::MaterialPreset::material)
      .def_readonly("source", &reflectance::MaterialPreset::source)
      .def_readonly("note", &reflectance::MaterialPreset::note);
  m.def("material_presets", &reflectance::MaterialPresets,
        "Every named preset, seed 000's table then seed 004's.");
  m.def(
      "material",
      [](const std::string& name) { return reflectance::FindMaterialPreset(name).material; },
      py::arg("name"), "The preset material of that name (ValueError lists the known names).");
}

}  // namespace iphong::python
