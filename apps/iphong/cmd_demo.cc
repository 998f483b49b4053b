// `iphong demo`: the main job on a built-in default. Today: the seed-002 worked example, a
// per-pixel Phong-shaded sphere and a sheet of the material presets.
#include <cstdio>
#include <filesystem>
#include <string>

#include "geometry/analytic.h"
#include "io/image_io.h"
#include "iphong/commands.h"
#include "reflectance/lighting.h"
#include "reflectance/material.h"
#include "render/shade_normal_map.h"

namespace iphong::cli {
namespace {

using reflectance::Light;
using reflectance::Lighting;
using reflectance::Material;

struct DemoOptions {
  std::string output_dir = "iphong-demo";
  int size = 256;
};

// Seed 002's numbers. The seed's V points from the viewer to the surface; iphong's view
// direction points toward the viewer, so it is negated (R·V is unchanged).
void PrintSeed002Example() {
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
  std::printf("Seed 002 worked example (Phong, 2 lights, the second behind the surface):\n");
  const Vec3d seed(0.39272, 0.13292, 0.12634);
  std::printf(
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

ImageF RenderSphere(int size, const Material& material, const Lighting& lighting) {
  geometry::Camera camera;
  camera.width = camera.height = size;
  camera.extent = 2.0;
  const auto surface = geometry::SampleSphere(camera, Vec3d::Zero(), 0.8);
  return render::ShadeSurfaceMap(surface, camera, material, lighting, reflectance::ModelOptions{});
}

// Every preset as a sphere, tiled left to right, top to bottom.
ImageF RenderPresetSheet(int tile, const Lighting& lighting) {
  const auto& presets = reflectance::MaterialPresets();
  const int columns = 5;
  const int rows = (static_cast<int>(presets.size()) + columns - 1) / columns;
  ImageF sheet(columns * tile, rows * tile, 3, 0.05f);
  for (std::size_t i = 0; i < presets.size(); ++i) {
    const ImageF sphere = RenderSphere(tile, presets[i].material, lighting);
    const int x0 = static_cast<int>(i % columns) * tile;
    const int y0 = static_cast<int>(i / columns) * tile;
    for (int row = 0; row < tile; ++row) {
      for (int col = 0; col < tile; ++col) {
        const float* src = sphere.at(col, row);
        if (src[0] == 0 && src[1] == 0 && src[2] == 0) continue;
        float* dst = sheet.at(x0 + col, y0 + row);
        for (int c = 0; c < 3; ++c) dst[c] = src[c];
      }
    }
  }
  return sheet;
}

void RunDemo(const DemoOptions& options) {
  if (options.size < 8 || options.size > 8192) {
    throw std::invalid_argument("--size must be in 8..8192");
  }
  PrintSeed002Example();

  Material material;  // the scene of the renderer issue
  material.ka = Vec3d(0.1, 0.1, 0.1);
  material.kd = Vec3d(0.9, 0.2, 0.1);
  material.ks = Vec3d(0.5, 0.5, 0.4);
  material.shininess = 10;
  const Lighting lighting = DemoLighting();
  const ImageF sphere = RenderSphere(options.size, material, lighting);
  const ImageF sheet = RenderPresetSheet(128, lighting);

  std::filesystem::create_directories(options.output_dir);
  const std::string sphere_path = options.output_dir + "/sphere.png";
  const std::string sheet_path = options.output_dir + "/materials.png";
  io::WriteImage(sphere_path, sphere);
  io::WriteImage(sheet_path, sheet);
  std::printf("\nShaded sphere (per-pixel Phong, light [0.3 0.4 0.866]): %s\n",
              sphere_path.c_str());
  std::printf("Material presets (`iphong materials` lists them):        %s\n", sheet_path.c_str());
}

}  // namespace

void AddDemoCommand(CLI::App& app) {
  auto options = std::make_shared<DemoOptions>();
  auto* cmd = app.add_subcommand("demo", "Run iphong on a built-in scene and say what it wrote");
  cmd->add_option("-o,--output", options->output_dir, "Output directory")->capture_default_str();
  cmd->add_option("--size", options->size, "Sphere image size in pixels")->capture_default_str();
  cmd->callback([options] { RunDemo(*options); });
}

}  // namespace iphong::cli
