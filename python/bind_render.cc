// Python view of src/render and src/io: render scenes and read datasets into numpy arrays.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cstring>

#include "arrays.h"
#include "bindings.h"
#include "io/dataset.h"
#include "io/scene_file.h"
#include "render/renderer.h"

namespace py = pybind11;

namespace iphong::python {
namespace {

py::dict RenderScene(const io::SceneFile& file, bool per_light) {
  render::RenderOutput out;
  {
    py::gil_scoped_release release;
    out = render::Render(file.scene, file.options, per_light);
  }
  py::dict result;
  result["image"] = ToArray(out.image);
  if (per_light) result["images"] = Stack(out.per_light);
  result["normals"] = ToArray(out.normal_cam);
  result["depth"] = ToArray(out.depth);
  result["albedo"] = ToArray(out.albedo);
  result["mask"] = ToArray(out.mask);
  std::vector<Vec3d> directions, intensities;
  for (const auto& light : file.scene.lighting.lights) {
    directions.push_back(light.type == reflectance::LightType::kDirectional
                             ? light.direction_cam
                             : Vec3d(light.position_cam.normalized()));
    intensities.push_back(light.diffuse_intensity);
  }
  result["light_directions"] = ToArray(directions);
  result["light_intensities"] = ToArray(intensities);
  return result;
}

}  // namespace

void BindRender(py::module_& m) {
  // std::runtime_error from io (a file or field named in the message) becomes ValueError too:
  // for Python callers it is bad input, like the rest.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const std::runtime_error& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  m.def(
      "_render_json",
      [](const std::string& text, const std::string& source, const std::string& base_dir,
         bool per_light) { return RenderScene(io::ParseScene(text, source, base_dir), per_light); },
      py::arg("text"), py::arg("source"), py::arg("base_dir"), py::arg("per_light"));
  m.def(
      "_render_file",
      [](const std::string& path, bool per_light) {
        return RenderScene(io::LoadSceneFile(path), per_light);
      },
      py::arg("path"), py::arg("per_light"));

  m.def(
      "load_dataset",
      [](const std::string& directory) {
        io::Dataset d;
        {
          py::gil_scoped_release release;
          d = io::LoadDataset(directory);
        }
        py::dict result;
        result["images"] = Stack(d.images);
        result["filenames"] = d.filenames;
        result["light_directions"] = ToArray(d.light_directions);
        result["light_intensities"] = ToArray(d.light_intensities);
        result["mask"] = ToArray(d.mask);
        result["normal_gt"] =
            d.normal_gt.pixels.empty() ? py::object(py::none()) : py::object(ToArray(d.normal_gt));
        if (d.material) {
          py::dict material;
          material["model"] = reflectance::LobeName(d.material->model);
          material["ambient"] = d.material->ambient;
          material["ka"] = d.material->material.ka;
          material["ks"] = d.material->material.ks;
          material["shininess"] = d.material->material.shininess;
          if (d.material->kd_known) material["kd"] = d.material->material.kd;
          result["material"] = material;
        } else {
          result["material"] = py::none();
        }
        result["warnings"] = d.warnings;
        return result;
      },
      py::arg("directory"),
      R"doc(Read a dataset directory (DiLiGenT layout) into numpy arrays:
images (K, H, W, 3) float32 linear, light_directions (K, 3), light_intensities (K, 3),
mask (H, W) bool, normal_gt (H, W, 3) or None, material (dict) or None, filenames, warnings.
Raises ValueError naming the file (and line) on bad input.)doc");
}

}  // namespace iphong::python
