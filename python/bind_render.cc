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

// The memory limit of a call: max_memory_gb, or the default (3/4 of the machine's).
MemoryLimit Limit(const py::object& max_memory_gb) {
  MemoryLimit limit;
  limit.knob = "max_memory_gb=";
  if (!max_memory_gb.is_none()) {
    const double gb = ToNumber(max_memory_gb, "max_memory_gb");
    if (!(gb > 0)) throw std::invalid_argument("max_memory_gb: expected a number > 0");
    limit.bytes = static_cast<std::uint64_t>(gb * 1e9);
  }
  return limit;
}

py::dict RenderScene(io::SceneFile file, bool per_light, const MemoryLimit& memory) {
  render::RenderOutput out;
  file.options.memory = memory;
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
  m.def(
      "_render_json",
      [](const std::string& text, const std::string& source, const std::string& base_dir,
         bool per_light, const py::object& max_memory_gb) {
        const MemoryLimit memory = Limit(max_memory_gb);
        return RenderScene(io::ParseScene(text, source, base_dir, memory), per_light, memory);
      },
      py::arg("text"), py::arg("source"), py::arg("base_dir"), py::arg("per_light"),
      py::arg("max_memory_gb") = py::none());
  m.def(
      "_render_file",
      [](const std::string& path, bool per_light, const py::object& max_memory_gb) {
        const MemoryLimit memory = Limit(max_memory_gb);
        return RenderScene(io::LoadSceneFile(path, memory), per_light, memory);
      },
      py::arg("path"), py::arg("per_light"), py::arg("max_memory_gb") = py::none());

  m.def(
      "load_dataset",
      [](const std::string& directory, const py::object& max_memory_gb) {
        io::Dataset d;
        io::DatasetLoadOptions options;
        options.memory = Limit(max_memory_gb);
        {
          py::gil_scoped_release release;
          d = io::LoadDataset(directory, options);
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
      py::arg("directory"), py::arg("max_memory_gb") = py::none(),
      R"doc(Read a dataset directory (DiLiGenT layout) into numpy arrays:
images (K, H, W, 3) float32 linear, light_directions (K, 3), light_intensities (K, 3),
mask (H, W) bool, normal_gt (H, W, 3) or None, material (dict) or None, filenames, warnings.
Raises ValueError naming the file (and line) on bad input, and when the images would need more
memory than max_memory_gb (default: three quarters of the machine's).)doc");
}

}  // namespace iphong::python
