#include "io/dataset_write.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <mutex>
#include <stdexcept>

#include "core/parallel.h"
#include "core/version.h"
#include "io/dataset_text.h"
#include "io/files.h"
#include "io/image_io.h"
#include "io/normal_mat.h"
#include "io/visualize.h"

namespace iphong::io {
namespace {

ImageF MaskImage(const Mask& mask) {
  ImageF image(mask.width, mask.height, 1);
  for (std::size_t p = 0; p < mask.inside.size(); ++p) image.pixels[p] = mask.inside[p] ? 1.0f : 0;
  return image;
}

nlohmann::json MaterialJson(const render::Scene& scene, const render::RenderOptions& options) {
  const auto& first = scene.objects.front();
  bool shared = true, kd_uniform = true;
  for (const auto& o : scene.objects) {
    shared = shared && o.material.ka == first.material.ka && o.material.ks == first.material.ks &&
             o.material.shininess == first.material.shininess;
    kd_uniform =
        kd_uniform && o.material.kd == first.material.kd && o.albedo_texture.pixels.empty();
  }
  auto rgb = [](const Vec3d& v) { return nlohmann::json::array({v[0], v[1], v[2]}); };
  nlohmann::json j;
  j["model"] = reflectance::LobeName(options.model.lobe);
  j["ambient"] = rgb(scene.lighting.ambient);
  if (!shared) {
    j["comment"] = "objects differ in ka, ks or shininess; these are the first object's";
  }
  j["ka"] = rgb(first.material.ka);
  j["ks"] = rgb(first.material.ks);
  j["shininess"] = first.material.shininess;
  if (kd_uniform) j["kd"] = rgb(first.material.kd);
  return j;
}

// A scene point in the main camera's frame (origin at its eye or view centre).
Vec3d ToCamera(const geometry::Camera& camera, const Vec3d& point) {
  return camera.rotation * (point - camera.center);
}

// The mean of the visible surface's points, camera frame.
Vec3d VisibleCentre(const geometry::Camera& camera, const render::RenderOutput& output) {
  Vec3d sum = Vec3d::Zero();
  std::size_t n = 0;
  for (int row = 0; row < output.mask.height; ++row) {
    for (int col = 0; col < output.mask.width; ++col) {
      if (!output.mask.at(col, row)) continue;
      const double depth =
          output.depth.pixels[static_cast<std::size_t>(row) * output.mask.width + col];
      sum += ToCamera(camera, camera.Unproject(col + 0.5, row + 0.5, depth));
      ++n;
    }
  }
  return n ? Vec3d(sum / static_cast<double>(n)) : Vec3d(0, 0, -1);
}

}  // namespace

RenderedNearLights NearLightsOf(const render::Scene& scene, const render::RenderOutput& output) {
  RenderedNearLights near;
  const Vec3d centre = VisibleCentre(scene.camera, output);
  for (const reflectance::Light& light : scene.lighting.lights) {
    const Vec3d position = ToCamera(scene.camera, light.position_cam);
    near.positions_mm.push_back(position);
    near.axes.push_back(scene.camera.rotation * light.axis_cam);
    near.anisotropy.push_back(light.anisotropy);
    near.directions.push_back((position - centre).normalized());
    near.leds = near.leds || light.anisotropy > 0;
  }
  near.camera.perspective = scene.camera.type == geometry::CameraType::kPerspective;
  near.camera.fx = scene.camera.fx;
  near.camera.fy = scene.camera.fy;
  near.camera.cx = scene.camera.cx;
  near.camera.cy = scene.camera.cy;
  near.camera.pixel_size = near.camera.perspective ? 0.0 : scene.camera.pixel_size();
  if (!near.camera.perspective) {
    double front = 0;
    for (const Vec3d& p : near.positions_mm) front = std::max(front, p.z());
    for (std::size_t p = 0; p < output.mask.inside.size(); ++p) {
      if (output.mask.inside[p]) front = std::max(front, -double(output.depth.pixels[p]));
    }
    near.depth_shift = front;
    for (Vec3d& p : near.positions_mm) p.z() -= front;
  }
  return near;
}

namespace {

// The near-light layout's own files (io/near_capture.h), scene units taken as mm.
void WriteNearLightFiles(OutputFolder& out, const std::string& prefix, const render::Scene& scene,
                         const render::RenderOutput& output) {
  auto file = [&](const std::string& name) { return out.file(prefix + name); };
  const RenderedNearLights near = NearLightsOf(scene, output);
  WriteTextFile(file("light_positions.txt"), FormatTriples(near.positions_mm));
  if (near.leds) {
    std::string anisotropy;
    for (double mu : near.anisotropy) anisotropy += std::to_string(mu) + "\n";
    WriteTextFile(file("light_axes.txt"), FormatTriples(near.axes));
    WriteTextFile(file("light_anisotropy.txt"), anisotropy);
  }
  WriteTextFile(file("camera.json"), FormatCameraJson(near.camera));
  ImageF depth = output.depth;
  for (std::size_t p = 0; p < depth.pixels.size(); ++p) {
    if (output.mask.inside[p]) depth.pixels[p] += static_cast<float>(near.depth_shift);
  }
  WriteMatImage(file("Depth_gt.mat"), "Depth_gt", depth);
}

}  // namespace

std::string CheckDatasetLights(const render::Scene& scene) {
  const auto& lights = scene.lighting.lights;
  if (lights.empty()) return "";
  const bool near = lights[0].type == reflectance::LightType::kPoint;
  for (std::size_t j = 0; j < lights.size(); ++j) {
    if ((lights[j].type == reflectance::LightType::kPoint) != near) {
      return "light " + std::to_string(j + 1) + " is " + (near ? "directional" : "a point light") +
             " and light 1 " + (near ? "a point light" : "directional") +
             "; a per-light dataset has directional lights (DiLiGenT layout) or point lights "
             "(the near-light layout), not both";
    }
    if (near && !lights[j].inverse_square_falloff) {
      return "light " + std::to_string(j + 1) +
             " is a point light without falloff; the near-light layout models the "
             "inverse-square law (set \"falloff\": true)";
    }
  }
  return "";
}

namespace {

bool HasPointLights(const render::Scene& scene) {
  return !scene.lighting.lights.empty() &&
         scene.lighting.lights[0].type == reflectance::LightType::kPoint;
}

}  // namespace

void WriteDatasetFiles(OutputFolder& out, const std::string& prefix, const DatasetToWrite& d,
                       const OutputSettings& settings) {
  const std::size_t k = d.images.size();
  if (k == 0) throw std::invalid_argument("a dataset needs at least one image");
  const ImageF& first = *d.images[0];
  for (std::size_t j = 0; j < k; ++j) {
    const ImageF* image = d.images[j];
    if (image->width != first.width || image->height != first.height || image->channels != 3) {
      throw std::invalid_argument("the images must all be " + SizeText(first.width, first.height) +
                                  " RGB");
    }
    // What LoadDataset would refuse is not written: a NaN in a float image is kept by the file.
    std::size_t bad = 0, at = 0;
    for (std::size_t p = 0; p < image->pixel_count(); ++p) {
      const float* v = image->pixels.data() + 3 * p;
      if (std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])) continue;
      if (bad++ == 0) at = p;
    }
    if (bad > 0) {
      throw std::invalid_argument("image " + std::to_string(j + 1) + " has " + std::to_string(bad) +
                                  " pixel(s) that are not finite (NaN or infinite; the first at "
                                  "column " +
                                  std::to_string(at % image->width) + ", row " +
                                  std::to_string(at / image->width) + ")");
    }
  }
  if (d.light_directions.size() != k ||
      (!d.light_intensities.empty() && d.light_intensities.size() != k)) {
    throw std::invalid_argument(std::to_string(k) + " images need " + std::to_string(k) +
                                " light directions and intensities");
  }
  const Mask whole(first.width, first.height, true);
  const Mask& mask = d.mask ? *d.mask : whole;
  if (mask.width != first.width || mask.height != first.height) {
    throw std::invalid_argument("the mask is " + SizeText(mask.width, mask.height) +
                                ", the images " + SizeText(first.width, first.height));
  }
  if (d.normal_gt && (d.normal_gt->width != first.width || d.normal_gt->height != first.height ||
                      d.normal_gt->channels != 3)) {
    throw std::invalid_argument("the ground truth must be " + SizeText(first.width, first.height) +
                                " x 3");
  }
  if (d.normal_gt) RequireUnitNormals(*d.normal_gt, &mask, "the ground truth");
  auto file = [&](const std::string& name) { return out.file(prefix + name); };
  const std::string ext = settings.extension();
  std::string names;
  const int digits = std::max<int>(3, std::to_string(k).size());
  // The images are encoded side by side (each file alone: the same bytes as one after another);
  // the first failure in image order is reported.
  std::vector<std::function<void()>> writes;
  std::mutex progress_mutex;
  std::size_t written = 0;
  for (std::size_t j = 0; j < k; ++j) {
    std::string number = std::to_string(j + 1);
    number.insert(0, digits - number.size(), '0');
    writes.push_back([&, j, path = file(number + ext)] {
      WriteImage(path, *d.images[j], settings.write_options());
      if (!d.progress) return;
      const std::lock_guard<std::mutex> lock(progress_mutex);
      d.progress(static_cast<double>(++written) / static_cast<double>(k));
    });
    names += number + ext + "\n";
  }
  RunTasks(writes, d.threads);
  WriteTextFile(file("filenames.txt"), names);
  WriteTextFile(file("light_directions.txt"), FormatTriples(d.light_directions));
  WriteTextFile(file("light_intensities.txt"),
                FormatTriples(d.light_intensities.empty() ? std::vector<Vec3d>(k, Vec3d::Ones())
                                                          : d.light_intensities));
  WriteImage(file("mask.png"), MaskImage(mask), {8, Encoding::kLinear});
  if (d.normal_gt) {
    WriteImage(file("normals.exr"), *d.normal_gt);
    WriteImage(file("normals.png"), NormalMapPicture(*d.normal_gt, mask), {16, Encoding::kData});
    WriteNormalMat(file("Normal_gt.mat"), "Normal_gt", *d.normal_gt);
  }
  if (!d.material_json.empty()) WriteTextFile(file("material.json"), d.material_json);
}

void WriteRenderOutput(OutputFolder& out, const std::string& prefix, const render::Scene& scene,
                       const render::RenderOptions& options, const render::RenderOutput& output,
                       const OutputSettings& settings, bool per_light,
                       const std::function<void(double)>& progress) {
  if (per_light) {
    if (std::string m = CheckDatasetLights(scene); !m.empty()) throw std::invalid_argument(m);
  }
  auto file = [&](const std::string& name) { return out.file(prefix + name); };
  const std::string material = MaterialJson(scene, options).dump(2) + "\n";
  const bool near = per_light && HasPointLights(scene);
  if (near) WriteNearLightFiles(out, prefix, scene, output);
  if (per_light) {
    DatasetToWrite d;
    // Near lights: the directions toward them from the visible surface's mean point, so a
    // distant-light reader gets the lights as the object's centre sees them.
    const RenderedNearLights rig = near ? NearLightsOf(scene, output) : RenderedNearLights{};
    for (std::size_t j = 0; j < output.per_light.size(); ++j) {
      const reflectance::Light& light = scene.lighting.lights[j];
      d.images.push_back(&output.per_light[j]);
      d.light_directions.push_back(near ? rig.directions[j] : light.direction_cam);
      d.light_intensities.push_back(light.diffuse_intensity);
    }
    d.mask = &output.mask;
    d.normal_gt = &output.normal_cam;
    d.material_json = material;
    d.progress = progress;
    d.threads = options.threads;
    WriteDatasetFiles(out, prefix, d, settings);
  } else {
    WriteImage(file("image" + settings.extension()), output.image, settings.write_options());
    WriteImage(file("mask.png"), MaskImage(output.mask), {8, Encoding::kLinear});
    WriteImage(file("normals.exr"), output.normal_cam);
    WriteImage(file("normals.png"), NormalMapPicture(output.normal_cam, output.mask),
               {16, Encoding::kData});
    WriteNormalMat(file("Normal_gt.mat"), "Normal_gt", output.normal_cam);
    WriteTextFile(file("material.json"), material);
  }
  WriteImage(file("depth.exr"), output.depth);
  WriteImage(file("albedo.exr"), output.albedo);
  nlohmann::json meta;
  meta["generator"] = "iphong render";
  meta["iphong_version"] = kVersion;
  meta["images"] = per_light ? output.per_light.size() : 1;
  meta["format"] = settings.format;
  meta["bits"] = settings.format == "exr" ? 32 : settings.bits;
  meta["encoding"] =
      settings.format == "exr" || settings.encoding == Encoding::kLinear ? "linear" : "srgb";
  meta["shading"] = render::ShadingName(options.shading);
  meta["camera"] =
      scene.camera.type == geometry::CameraType::kOrthographic ? "orthographic" : "perspective";
  meta["depth"] = "distance along the view axis in scene units; 0 outside the mask";
  if (per_light && HasPointLights(scene)) {
    meta["near_lights"] =
        "light_positions.txt, camera.json and Depth_gt.mat in the camera frame, scene units as mm";
  }
  meta["frame"] = "camera frame: x right, y up, z toward the viewer; row 0 at the top";
  meta["supersampling"] = options.supersampling;
  meta["shadows"] = options.shadows;
  meta["noise"] = {{"gaussian_sigma", options.noise.gaussian_sigma},
                   {"shot_photons", options.noise.shot_photons},
                   {"quantization_bits", options.noise.quantization_bits},
                   {"seed", options.noise.seed}};
  WriteTextFile(file("render.json"), meta.dump(2) + "\n");
}

}  // namespace iphong::io
