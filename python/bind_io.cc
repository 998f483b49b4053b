// Python view of src/io's writers: the files the command line writes, from numpy arrays, through
// the same code (verified writes; a folder appears complete or not at all; nothing is replaced
// unless `overwrite`).
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cstring>
#include <filesystem>

#include "arrays.h"
#include "bindings.h"
#include "io/dataset.h"
#include "io/dataset_write.h"
#include "io/files.h"
#include "io/image_io.h"
#include "io/mesh_io.h"
#include "io/output_folder.h"
#include "io/surface.h"
#include "io/visualize.h"

namespace py = pybind11;

namespace iphong::python {
namespace {

ImageF ToSingle(const py::object& value, const char* what) {
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 2)
    throw std::invalid_argument(std::string(what) + " must have shape (H, W)");
  ImageF image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)), 1);
  std::memcpy(image.pixels.data(), a.data(), image.pixels.size() * sizeof(float));
  return image;
}

void RequireSize(const ImageF& image, int width, int height, const char* what) {
  if (image.width != width || image.height != height) {
    throw std::invalid_argument(std::string(what) + " is " + SizeText(image.width, image.height) +
                                ", expected " + SizeText(width, height));
  }
}

}  // namespace

void BindIo(py::module_& m) {
  // "" when `bytes` fit the limit max_memory_gb= gives (or the default), else the refusal's
  // text: the wrappers check an array's copies before numpy makes them.
  m.def(
      "_check_memory",
      [](double bytes, const py::object& max_memory_gb, const std::string& what) {
        return MemoryLimitFrom(max_memory_gb).Check(bytes, what);
      },
      py::arg("bytes"), py::arg("max_memory_gb"), py::arg("what"));
  m.def(
      "_srgb_to_linear",
      [](const py::array_t<float, py::array::c_style | py::array::forcecast>& values) {
        py::array_t<float> out(
            std::vector<py::ssize_t>(values.shape(), values.shape() + values.ndim()));
        const float* in = values.data();
        float* o = out.mutable_data();
        for (py::ssize_t i = 0; i < values.size(); ++i) o[i] = io::SrgbToLinear(in[i]);
        return out;
      },
      py::arg("values"));

  m.def(
      "_save_normals",
      [](const std::string& path, const py::object& normals_in, const py::object& mask_in,
         const std::string& convention, bool overwrite) {
        const ImageF normals = ToImage(normals_in, "normals");
        const Mask mask = mask_in.is_none() ? NonZeroPixels(normals)
                                            : ToMask(mask_in, normals.width, normals.height);
        // NaN or non-unit normals: the same refusal as the commands that read maps.
        io::RequireUnitNormals(normals, &mask, "normals");
        const std::string ext = io::LowerExtension(path);
        if (ext != ".exr" && ext != ".png" && ext != ".tif" && ext != ".tiff") {
          throw std::invalid_argument(path +
                                      ": expected .exr or .tif (float xyz) or .png (picture)");
        }
        if (convention != "opengl" && convention != "directx") {
          throw std::invalid_argument("convention must be 'opengl' or 'directx'");
        }
        py::gil_scoped_release release;
        io::WriteSingleOutputFile("python", path, overwrite, {}, [&](const std::string& temp) {
          if (ext == ".png") {
            io::WriteImage(temp, io::NormalMapPicture(normals, mask, convention == "directx"),
                           {16, io::Encoding::kData});
          } else {
            ImageF masked = normals;
            for (std::size_t p = 0; p < mask.inside.size(); ++p)
              if (!mask.inside[p]) std::fill_n(masked.pixels.data() + 3 * p, 3, 0.0f);
            io::WriteImage(temp, masked);
          }
        });
      },
      py::arg("path"), py::arg("normals"), py::arg("mask"), py::arg("convention"),
      py::arg("overwrite"));

  m.def(
      "_save_mesh",
      [](const std::string& path, const py::object& height_in, const py::object& mask_in,
         const py::object& normals_in, const py::object& albedo_in, double pixel_size,
         bool overwrite) {
        const ImageF height = ToSingle(height_in, "height");
        Mask mask = mask_in.is_none() ? Mask(height.width, height.height, true)
                                      : ToMask(mask_in, height.width, height.height);
        ImageF normals, albedo;
        if (!normals_in.is_none()) {
          normals = ToImage(normals_in, "normals");
          RequireSize(normals, height.width, height.height, "normals");
        }
        if (!albedo_in.is_none()) {
          albedo = ToImage(albedo_in, "albedo");
          RequireSize(albedo, height.width, height.height, "albedo");
        }
        const std::string ext = io::LowerExtension(path);
        if (ext != ".ply" && ext != ".obj") {
          throw std::invalid_argument(path + ": expected .ply or .obj");
        }
        geometry::HeightMapFrame frame;
        frame.pixel_size = pixel_size;
        if (auto message = frame.Validate(); !message.empty()) {
          throw std::invalid_argument(message);
        }
        io::HeightMesh built;
        {
          py::gil_scoped_release release;  // held again before the tuple is made
          built =
              io::MakeHeightMesh(height, mask, frame, normals.pixels.empty() ? nullptr : &normals,
                                 nullptr, albedo.pixels.empty() ? nullptr : &albedo);
          if (built.mesh.triangles.empty()) {
            throw std::invalid_argument("height: no 2x2 block of finite heights inside the mask");
          }
          io::WriteSingleOutputFile("python", path, overwrite, {}, [&](const std::string& temp) {
            io::SaveMesh(temp, built.mesh, built.colors.empty() ? nullptr : &built.colors);
          });
        }
        return py::make_tuple(built.mesh.positions.size(), built.mesh.triangles.size());
      },
      py::arg("path"), py::arg("height"), py::arg("mask"), py::arg("normals"), py::arg("albedo"),
      py::arg("pixel_size"), py::arg("overwrite"));

  m.def(
      "_save_dataset",
      [](const std::string& directory, const py::object& images_in,
         const py::object& light_directions, const py::object& light_intensities,
         const py::object& mask_in, const py::object& normal_gt_in, const std::string& format,
         int bits, bool overwrite) {
        const FloatStack a = ToImageStack(images_in);
        const std::size_t k = a.shape(0);
        const int h = static_cast<int>(a.shape(1)), w = static_cast<int>(a.shape(2));
        std::vector<ImageF> images(k, ImageF(w, h, 3));
        for (std::size_t j = 0; j < k; ++j) {
          std::memcpy(images[j].pixels.data(), a.data() + j * h * w * 3,
                      images[j].pixels.size() * sizeof(float));
        }
        io::DatasetToWrite d;
        for (const ImageF& image : images) d.images.push_back(&image);
        d.light_directions = ToRows(light_directions, k, "light_directions");
        for (Vec3d& l : d.light_directions) {
          if (!(l.norm() > 0)) throw std::invalid_argument("light_directions: a zero direction");
          l.normalize();
        }
        if (!light_intensities.is_none()) {
          d.light_intensities = ToIntensities(light_intensities, k);
        }
        const Mask mask = mask_in.is_none() ? Mask(w, h, true) : ToMask(mask_in, w, h);
        d.mask = &mask;
        ImageF normal_gt;
        if (!normal_gt_in.is_none()) {
          normal_gt = ToImage(normal_gt_in, "normal_gt");
          d.normal_gt = &normal_gt;
        }
        io::OutputSettings settings;
        if (format != "png" && format != "exr") {
          throw std::invalid_argument("format must be 'png' or 'exr'");
        }
        if (bits != 8 && bits != 16) throw std::invalid_argument("bits must be 8 or 16");
        settings.format = format;
        settings.bits = bits;
        py::gil_scoped_release release;
        io::OutputFolderOptions folder;
        folder.command = "save_dataset";
        folder.overwrite = overwrite;
        io::OutputFolder out(directory, folder);
        io::WriteDatasetFiles(out, "", d, settings);
        out.Commit();
      },
      py::arg("directory"), py::arg("images"), py::arg("light_directions"),
      py::arg("light_intensities"), py::arg("mask"), py::arg("normal_gt"), py::arg("format"),
      py::arg("bits"), py::arg("overwrite"));
}

}  // namespace iphong::python
