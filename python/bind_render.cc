// Python view of src/render and src/io: render scenes and read datasets into numpy arrays.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstring>

#include "arrays.h"
#include "bindings.h"
#include "io/dataset.h"
#include "io/dataset_write.h"
#include "io/scene_file.h"
#include "render/renderer.h"

namespace py = pybind11;

namespace iphong::python {
namespace {

// camera.json's content as a dict: fx, fy, cx, cy (OpenCV's principal point) or pixel_size.
py::dict CameraDict(const io::CameraIntrinsics& c) {
  py::dict out;
  if (c.perspective) {
    out["fx"] = c.fx;
    out["fy"] = c.fy;
    out["cx"] = c.cx - 0.5;
    out["cy"] = c.cy - 0.5;
  } else {
    out["pixel_size"] = c.pixel_size;
  }
  return out;
}

py::dict RenderScene(io::SceneFile file, bool per_light, const MemoryLimit& memory) {
  render::RenderOutput out;
  file.options.memory = memory;
  {
    py::gil_scoped_release release;
    out = render::Render(file.scene, file.options, per_light);
    // A blank render is a scene mistake (what `iphong render` refuses), not a picture.
    if (out.mask.count() == 0) {
      throw std::invalid_argument("nothing is visible: " +
                                  render::NothingVisibleReason(file.scene, file.options));
    }
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
  if (per_light && file.scene.lighting.HasPointLights()) {
    if (std::string m = io::CheckDatasetLights(file.scene); !m.empty()) {
      throw std::invalid_argument(m);
    }
    // The near-light layout's arrays (what `iphong render --per-light` writes).
    const io::RenderedNearLights near = io::NearLightsOf(file.scene, out);
    result["light_directions"] = ToArray(near.directions);
    result["light_positions"] = ToArray(near.positions_mm);
    result["light_axes"] = ToArray(near.axes);
    result["light_anisotropy"] = near.anisotropy;
    result["camera"] = CameraDict(near.camera);
  }
  return result;
}

}  // namespace

void BindRender(py::module_& m) {
  m.def(
      "_render_json",
      [](const std::string& text, const std::string& source, const std::string& base_dir,
         bool per_light, const py::object& max_memory_gb) {
        const MemoryLimit memory = MemoryLimitFrom(max_memory_gb);
        return RenderScene(io::ParseScene(text, source, base_dir, memory), per_light, memory);
      },
      py::arg("text"), py::arg("source"), py::arg("base_dir"), py::arg("per_light"),
      py::arg("max_memory_gb") = py::none());
  m.def(
      "_render_file",
      [](const std::string& path, bool per_light, const py::object& max_memory_gb) {
        const MemoryLimit memory = MemoryLimitFrom(max_memory_gb);
        return RenderScene(io::LoadSceneFile(path, memory), per_light, memory);
      },
      py::arg("path"), py::arg("per_light"), py::arg("max_memory_gb") = py::none());

  m.def(
      "load_dataset",
      [](const std::string& directory, const py::object& max_memory_gb, const std::string& lights,
         const std::string& intensities, const std::string& mask, const std::string& encoding,
         const py::object& crop, int downscale, const std::string& images) {
        io::Dataset d;
        io::DatasetLoadOptions options;
        options.memory = MemoryLimitFrom(max_memory_gb);
        options.capture.lights = lights;
        options.capture.intensities = intensities;
        options.capture.mask = mask;
        options.capture.images = images;
        options.capture.encoding = encoding;
        options.capture.downscale = downscale;
        if (!crop.is_none()) {
          const std::vector<double> r = ToNumbers(crop, 4, "crop (x, y, w, h)");
          for (double v : r) {
            if (v != std::floor(v) || std::abs(v) > 1e9) {
              throw std::invalid_argument("crop: expected four whole numbers (x, y, w, h)");
            }
          }
          options.capture.crop = {int(r[0]), int(r[1]), int(r[2]), int(r[3])};
        }
        if (std::string m = options.capture.Check(); !m.empty()) throw std::invalid_argument(m);
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
        if (d.files.near.present()) {
          const io::NearLightFiles& n = d.files.near;
          result["light_positions"] = ToArray(n.positions_mm);
          result["camera"] = CameraDict(n.camera);
          result["light_axes"] =
              n.axes.empty() ? py::object(py::none()) : py::object(ToArray(n.axes));
          result["light_anisotropy"] =
              n.anisotropy.empty() ? py::object(py::none()) : py::cast(n.anisotropy);
          result["depth_gt"] =
              d.depth_gt.pixels.empty() ? py::object(py::none()) : py::object(ToArray(d.depth_gt));
        } else {
          for (const char* key :
               {"light_positions", "camera", "light_axes", "light_anisotropy", "depth_gt"}) {
            result[key] = py::none();
          }
        }
        result["warnings"] = d.warnings;
        result["not_read"] = d.files.skipped;
        result["description"] = io::DescribeDataset(d);
        result["encoding"] = d.encoding.encoding == io::Encoding::kSrgb ? "srgb" : "linear";
        py::list counts;
        for (const io::ImageCounts& c : d.image_counts) {
          py::dict one;
          one["saturated_pixels"] = c.saturated;
          one["black_pixels"] = c.black;
          counts.append(one);
        }
        result["image_counts"] = counts;
        return result;
      },
      py::arg("directory"), py::arg("max_memory_gb") = py::none(), py::kw_only(),
      py::arg("lights") = "", py::arg("intensities") = "", py::arg("mask") = "",
      py::arg("encoding") = "auto", py::arg("crop") = py::none(), py::arg("downscale") = 1,
      py::arg("images") = "",
      R"doc(Read a capture folder into numpy arrays: any layout `iphong normals` reads (DiLiGenT,
UW, RTI .lp, a folder of images with a light file), with the same options (images: a list of the
photos in light order; lights, intensities, mask: files, intensities "none" for all 1 whatever
file the capture holds; encoding "auto"/"linear"/"srgb"; crop
(x, y, w, h) in the files' pixels; downscale N).
Returns images (K, H, W, 3) float32 linear, light_directions (K, 3), light_intensities (K, 3),
mask (H, W) bool, normal_gt (H, W, 3) or None, material (dict) or None, filenames, warnings,
not_read (files beside the photos taken for companions, an albedo picture or NAME.normals.dat, and
not read), description (what was read, one line), encoding, image_counts (saturated and black pixels); for a
near-light capture (light_positions.txt) also light_positions (K, 3) mm, camera (camera.json's
dict), light_axes (K, 3) and light_anisotropy (K) or None, depth_gt (H, W) mm or None (all None
otherwise): what estimate_normals takes.
Raises ValueError naming the file (and line) on bad input, and when the images would need more
memory than max_memory_gb (default: three quarters of the machine's).)doc");
}

}  // namespace iphong::python
