// `iphong demo`: the main job on a built-in default: the seed-002 worked example, the scan-line
// renderer checked against the analytic sphere, seed 001's shading comparison, a
// photometric-stereo dataset with ground truth, normals recovered from it, heights and a mesh
// integrated from those, and a sheet of the material presets.
#include <cstdio>
#include <filesystem>
#include <string>

#include <cmath>

#include "geometry/analytic.h"
#include "geometry/primitives.h"
#include "integrate/integrate.h"
#include "io/dataset.h"
#include "io/dataset_write.h"
#include "io/image_io.h"
#include "io/output_folder.h"
#include "io/scene_file.h"
#include "io/surface.h"
#include "io/visualize.h"
#include "iphong/commands.h"
#include "reflectance/lighting.h"
#include "reflectance/material.h"
#include "render/renderer.h"
#include "render/shade_normal_map.h"
#include "solve/metrics.h"
#include "solve/normals.h"

namespace iphong::cli {
namespace {

using reflectance::Light;
using reflectance::Lighting;
using reflectance::Material;

struct DemoOptions {
  std::string output_dir = "iphong-demo";
  int size = 256;
  CommonOptions common;
};

// Seed 002's numbers. The seed's V points from the viewer to the surface; iphong's view
// direction points toward the viewer, so it is negated (R·V is unchanged).
void PrintSeed002Example(const CommonOptions& common) {
  Material material;
  material.ka = Vec3d(0.1, 0.1, 0.1);
  material.kd = Vec3d(0.9, 0.0, 0.0);
  material.ks = Vec3d(0.5, 0.5, 0.4);
  material.shininess = 10;
  Lighting lighting;
  lighting.ambient = Rgb(1, 1, 1);
  lighting.lights = {Light::Directional(Vec3d(0.57735, 0.57735, 0.57735), Rgb(0.5, 0.5, 0.5)),
                     Light::Directional(Vec3d(0, 0, -1), Rgb(0.5, 0.5, 0.5))};
  const Vec3d normal_cam(0, 0, 1);
  const Vec3d view_cam = -Vec3d(0.23570, 0.23570, -0.94281);
  const Vec3d color = reflectance::Shade(normal_cam, view_cam.normalized(), Vec3d::Zero().eval(),
                                         material, lighting, reflectance::ModelOptions{});
  Say(common, "Seed 002 worked example (Phong, 2 lights, the second behind the surface):\n");
  const Vec3d seed(0.39272, 0.13292, 0.12634);
  Say(common,
      "  I = [%.6f %.6f %.6f]\n  seed 002 prints [0.39272 0.13292 0.12634] (it rounds each step);"
      " largest difference %.1e\n",
      color[0], color[1], color[2], (color - seed).cwiseAbs().maxCoeff());
}

Lighting DemoLighting() {
  Lighting lighting;
  lighting.ambient = Rgb(1, 1, 1);
  lighting.lights = {Light::Directional(Vec3d(0.3, 0.4, 0.866), Rgb(1, 1, 1))};
  return lighting;
}

// The renderer issue's scene, with 12 hemisphere lights added for the dataset.
constexpr const char* kDemoScene = R"({
  "width": 256, "height": 256,
  "camera": {"type": "orthographic", "extent": 2.0},
  "ambient": [1, 1, 1],
  "lights": [{"type": "directional", "direction": [0.3, 0.4, 0.866], "intensity": [1, 1, 1]}],
  "objects": [{"shape": "sphere", "center": [0, 0, 0], "radius": 0.8, "subdivisions": 6,
               "material": {"ka": [0.1, 0.1, 0.1], "kd": [0.9, 0.2, 0.1], "ks": [0.5, 0.5, 0.4],
                            "shininess": 10}}],
  "shading": "phong"})";

// Places `tile` at column `x0` of `strip` (same height).
void Paste(ImageF& strip, const ImageF& tile, int x0) {
  for (int row = 0; row < tile.height; ++row)
    for (int col = 0; col < tile.width; ++col)
      for (int c = 0; c < 3; ++c) strip.at(x0 + col, row)[c] = tile.at(col, row)[c];
}

// Every preset as a sphere, tiled left to right, top to bottom.
ImageF RenderPresetSheet(int tile, const Lighting& lighting, int threads) {
  const auto& presets = reflectance::MaterialPresets();
  const int columns = 5;
  const int rows = (static_cast<int>(presets.size()) + columns - 1) / columns;
  ImageF sheet(columns * tile, rows * tile, 3, 0.05f);
  render::Scene scene;
  scene.camera = geometry::Camera::Orthographic(tile, tile, 2.0);
  scene.lighting = lighting;
  scene.objects.resize(1);
  scene.objects[0].mesh = geometry::MakeSphere(0.8, 5);
  render::RenderOptions options;
  options.supersampling = 2;
  options.threads = threads;
  for (std::size_t i = 0; i < presets.size(); ++i) {
    scene.objects[0].material = presets[i].material;
    const render::RenderOutput out = render::Render(scene, options, false);
    const int x0 = static_cast<int>(i % columns) * tile;
    const int y0 = static_cast<int>(i / columns) * tile;
    for (int row = 0; row < tile; ++row) {
      for (int col = 0; col < tile; ++col) {
        const float* src = out.image.at(col, row);
        float* dst = sheet.at(x0 + col, y0 + row);
        // Blend the anti-aliased edge over the sheet's grey.
        const float coverage =
            out.mask.at(col, row) ? 1.0f : std::min(1.0f, src[0] + src[1] + src[2]);
        for (int c = 0; c < 3; ++c) dst[c] = src[c] + (1 - coverage) * dst[c];
      }
    }
  }
  return sheet;
}

void RunDemo(const DemoOptions& options) {
  if (options.size < 8 || options.size > 8192) {
    throw std::invalid_argument("--size must be in 8..8192");
  }
  PrintSeed002Example(options.common);

  // 1. The scene through the scan-line renderer, checked against the analytic sphere.
  io::SceneFile file = io::ParseScene(kDemoScene, "built-in demo scene", "");
  file.options.threads = options.common.threads;
  file.scene.camera = geometry::Camera::Orthographic(options.size, options.size, 2.0);
  const render::RenderOutput rendered = render::Render(file.scene, file.options, false);
  const auto analytic = geometry::SampleSphere(file.scene.camera, Vec3d::Zero(), 0.8);
  const ImageF exact =
      render::ShadeSurfaceMap(analytic, file.scene.camera, file.scene.objects[0].material,
                              file.scene.lighting, file.options.model);
  double error = 0;
  std::size_t n = 0;
  for (std::size_t p = 0; p < rendered.mask.inside.size(); ++p) {
    if (!rendered.mask.inside[p] || !analytic.mask.inside[p]) continue;
    for (int c = 0; c < 3; ++c)
      error += std::abs(rendered.image.pixels[3 * p + c] - exact.pixels[3 * p + c]);
    n += 3;
  }
  std::size_t triangles = file.scene.objects[0].mesh.triangle_count();

  // 2. Seed 001's comparison on a coarse sphere: flat, Gouraud, Phong.
  render::Scene coarse = file.scene;
  coarse.camera = geometry::Camera::Orthographic(256, 256, 2.0);
  coarse.objects[0].mesh = geometry::MakeSphere(0.8, 2);
  coarse.objects[0].material.shininess = 60;
  ImageF strip(3 * 256, 256, 3);
  int slot = 0;
  for (render::Shading shading :
       {render::Shading::kFlat, render::Shading::kGouraud, render::Shading::kPhong}) {
    render::RenderOptions o = file.options;
    o.shading = shading;
    o.supersampling = 2;
    Paste(strip, render::Render(coarse, o, false).image, 256 * slot++);
  }

  // 3. A photometric-stereo dataset with exact ground truth: 12 lights on a hemisphere.
  render::Scene lit = file.scene;
  lit.lighting.ambient = Vec3d::Zero();
  lit.lighting.lights.clear();
  for (int i = 0; i < 12; ++i) {
    const double z = 1 - 0.6 * (i + 0.5) / 12, r = std::sqrt(1 - z * z), a = 2.39996323 * i;
    // 0.6 keeps kd + ks below 1: nothing saturates in the 16-bit files.
    lit.lighting.lights.push_back(
        Light::Directional(Vec3d(r * std::cos(a), r * std::sin(a), z), Rgb::Constant(0.6)));
  }
  const render::RenderOutput dataset = render::Render(lit, file.options, true);

  // The demo's folder is its own: running it again replaces its earlier output (and only that).
  io::OutputFolderOptions folder;
  folder.command = "demo";
  folder.overwrite = true;
  io::OutputFolder out(options.output_dir, folder);
  const std::string dir = options.output_dir + "/";
  io::WriteImage(out.file("sphere.png"), rendered.image);
  io::WriteImage(out.file("shading.png"), strip);
  std::vector<std::string> names;
  for (const auto& preset : reflectance::MaterialPresets()) names.push_back(preset.name);
  io::WriteImage(out.file("materials.png"),
                 io::LabelTiles(RenderPresetSheet(128, DemoLighting(), options.common.threads), 128,
                                128, 22, names));
  io::OutputSettings png;
  png.format = "png";
  io::WriteRenderOutput(out, "sphere-dataset/", lit, file.options, dataset, png, true);

  // 4. The inverse: normals from the dataset just written (read back from disk), coefficients
  //    unknown, against the renderer's exact ground truth; Woodham beside it.
  io::DatasetLoadOptions load;
  load.threads = options.common.threads;
  io::Dataset data_set = io::LoadDataset(out.folder("sphere-dataset"), load);
  std::vector<const float*> images;
  for (const ImageF& image : data_set.images) images.push_back(image.pixels.data());
  const solve::PhotometricData observations =
      solve::GatherObservations(images, data_set.width(), data_set.height(), data_set.mask,
                                data_set.light_directions, data_set.light_intensities);
  solve::NormalOptions estimate;  // material.json is ignored: ks and shininess are estimated
  estimate.threads = options.common.threads;
  const solve::NormalResult recovered = solve::EstimateNormals(observations, estimate);
  estimate.model = reflectance::Lobe::kLambert;
  const solve::NormalResult woodham = solve::EstimateNormals(observations, estimate);
  const solve::AngularErrorMetrics phong_error =
      solve::CompareNormals(recovered.normals, data_set.normal_gt, data_set.mask);
  const solve::AngularErrorMetrics woodham_error =
      solve::CompareNormals(woodham.normals, data_set.normal_gt, data_set.mask);
  io::WriteImage(out.file("normals/normals.png"),
                 io::NormalMapPicture(recovered.normals, data_set.mask), {16, io::Encoding::kData});
  io::WriteImage(out.file("normals/normals.exr"), recovered.normals);
  io::WriteErrorMap(out.file("normals/error.png"), phong_error.error_deg, data_set.mask,
                    io::ErrorMapScale(phong_error.error_deg, data_set.mask));

  // 5. Heights and a mesh from the recovered normals, against the renderer's depth.
  integrate::IntegrateOptions integration;
  integration.pixel_size = file.scene.camera.pixel_size();
  integration.threads = options.common.threads;
  const integrate::IntegrateResult heights =
      integrate::IntegrateNormals(recovered.normals, data_set.mask, integration);
  double mean_difference = 0, squared = 0;
  std::size_t surface_pixels = 0;
  for (std::size_t p = 0; p < data_set.mask.inside.size(); ++p) {
    if (!data_set.mask.inside[p]) continue;
    mean_difference += heights.height.pixels[p] + dataset.depth.pixels[p];  // z = −depth + c
    ++surface_pixels;
  }
  mean_difference /= surface_pixels;
  for (std::size_t p = 0; p < data_set.mask.inside.size(); ++p) {
    if (!data_set.mask.inside[p]) continue;
    const double e = heights.height.pixels[p] + dataset.depth.pixels[p] - mean_difference;
    squared += e * e;
  }
  const double height_rmse = std::sqrt(squared / surface_pixels);
  io::SurfaceFileOptions surface_files;
  surface_files.albedo = &recovered.albedo;
  const io::SurfaceFiles surface =
      io::WriteSurfaceFiles(out, "surface/", heights, recovered.normals, data_set.mask,
                            io::FrameOf(integration), surface_files);
  out.Commit();

  Say(options.common, "\nScan-line renderer, %zu-triangle sphere, Phong shading, %dx%d:\n",
      triangles, options.size, options.size);
  Say(options.common,
      "  mean |rendered - analytic per-pixel Phong| = %.2e  (raster %.0f ms, shading %.0f ms)\n",
      error / n, 1e3 * rendered.raster_seconds, 1e3 * rendered.shade_seconds);
  Say(options.common, "\nNormals recovered from the 12-image dataset (coefficients unknown):\n");
  Say(options.common,
      "  model chosen by held-out prediction: %s, shininess %.1f, median ks [%.3f %.3f %.3f] "
      "(true phong, 10, [0.5 0.5 0.4]); normals: mean %.3f deg, median %.3f deg\n",
      reflectance::LobeName(recovered.model).c_str(), recovered.shininess, recovered.ks[0],
      recovered.ks[1], recovered.ks[2], phong_error.mean_deg, phong_error.median_deg);
  Say(options.common, "  Woodham (Lambertian least squares): mean %.2f deg\n",
      woodham_error.mean_deg);
  Say(options.common, "\nHeights integrated from the recovered normals (%s, %.0f ms):\n",
      integrate::MethodName(heights.summary.method), 1e3 * heights.summary.total_seconds);
  Say(options.common,
      "  RMSE against the true depth %.4f scene units (%.2f%% of the radius 0.8); "
      "mesh of %zu triangles\n",
      height_rmse, 100 * height_rmse / 0.8, surface.triangles);
  Say(options.common, "\nWrote:\n");
  Say(options.common, "  %-32s the sphere\n", (dir + "sphere.png").c_str());
  Say(options.common, "  %-32s flat | Gouraud | Phong on a 320-triangle sphere (seed 001)\n",
      (dir + "shading.png").c_str());
  Say(options.common, "  %-32s the 13 material presets (`iphong materials`)\n",
      (dir + "materials.png").c_str());
  Say(options.common, "  %-32s 12-light photometric-stereo dataset with ground truth\n",
      (dir + "sphere-dataset/").c_str());
  Say(options.common, "  %-32s recovered normals and their angular error map\n",
      (dir + "normals/").c_str());
  Say(options.common, "  %-32s heights, mesh.ply (MeshLab, Blender) and a rendered picture of it\n",
      (dir + "surface/").c_str());
}

}  // namespace

void AddDemoCommand(CLI::App& app) {
  auto options = std::make_shared<DemoOptions>();
  auto* cmd = app.add_subcommand("demo", "Run iphong on a built-in scene and say what it wrote");
  cmd->add_option("-o,--output", options->output_dir,
                  "Output folder: new or empty, or an earlier demo output (replaced)")
      ->capture_default_str();
  cmd->add_option("--size", options->size, "Sphere image size in pixels")
      ->check(CLI::Range(8, 8192))
      ->capture_default_str();
  AddThreadsOption(cmd, options->common);
  cmd->add_flag("-q,--quiet", options->common.quiet, "Print nothing but errors and warnings");
  cmd->callback([options] { RunDemo(*options); });
}

}  // namespace iphong::cli
