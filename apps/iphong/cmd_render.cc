// `iphong render SCENE.json -o DIR`: one image with all lights, or with --per-light a DiLiGenT
// dataset (one image per light) with exact ground truth.
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/errors.h"
#include "io/dataset.h"
#include "io/dataset_write.h"
#include "io/output_folder.h"
#include "io/scene_file.h"
#include "iphong/commands.h"
#include "iphong/console.h"

namespace iphong::cli {
namespace {

struct RenderCommandOptions {
  std::string scene_path;
  std::string output_dir;
  bool per_light = false;
  std::optional<std::string> format, encoding, shading;
  std::optional<int> bits, supersampling, seed;
  std::optional<double> noise_sigma;
  bool shadows = false;
  CommonOptions common;
};

void RunRender(const RenderCommandOptions& o) {
  io::SceneFile file = io::LoadSceneFile(o.scene_path, o.common.memory());
  if (o.format) file.output.format = *o.format;
  if (o.bits) file.output.bits = *o.bits;
  if (o.encoding)
    file.output.encoding = *o.encoding == "srgb" ? io::Encoding::kSrgb : io::Encoding::kLinear;
  if (o.shading) file.options.shading = render::ParseShading(*o.shading);
  if (o.supersampling) file.options.supersampling = *o.supersampling;
  if (o.shadows) file.options.shadows = true;
  if (o.noise_sigma) file.options.noise.gaussian_sigma = *o.noise_sigma;
  if (o.seed) file.options.noise.seed = static_cast<std::uint64_t>(*o.seed);
  file.options.threads = o.common.threads;
  file.options.memory = o.common.memory();
  if (o.per_light) {
    if (std::string m = io::CheckDatasetLights(file.scene); !m.empty()) {
      throw std::runtime_error(o.scene_path + ": " + m);
    }
  }
  // The folder is checked before the render: a refusal costs nothing.
  io::OutputFolderOptions folder;
  folder.command = "render";
  folder.overwrite = o.common.overwrite;
  folder.inputs = file.inputs;
  folder.inputs.push_back(o.scene_path);
  io::OutputFolder output(o.output_dir, folder);

  render::RenderOutput out;
  try {
    Progress progress("render", o.common.progress_mode());
    file.options.progress = [&progress](double f) { progress.Update(f); };
    out = render::Render(file.scene, file.options, o.per_light);
    file.options.progress = nullptr;
  } catch (const ResourceError& e) {
    throw ResourceError(o.scene_path + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(o.scene_path + ": " + e.what());
  }
  if (out.mask.count() == 0) {
    throw std::runtime_error(o.scene_path + ": nothing is visible: " +
                             render::NothingVisibleReason(file.scene, file.options));
  }
  {
    Progress write("write", o.common.progress_mode());
    io::WriteRenderOutput(output, "", file.scene, file.options, out, file.output, o.per_light,
                          [&write](double f) { write.Update(f); });
  }
  output.Commit();

  std::size_t triangles = 0;
  for (const auto& object : file.scene.objects) triangles += object.mesh.triangle_count();
  PrintJson(o.common, nlohmann::json({{"output", o.output_dir},
                                      {"width", file.scene.camera.width},
                                      {"height", file.scene.camera.height},
                                      {"triangles", triangles},
                                      {"lights", file.scene.lighting.lights.size()},
                                      {"images", o.per_light ? out.per_light.size() : 1},
                                      {"visible_pixels", out.mask.count()},
                                      {"raster_seconds", out.raster_seconds},
                                      {"shade_seconds", out.shade_seconds}})
                          .dump(2));
  Say(o.common,
      "Rendered %dx%d, %zu triangles, %zu lights, %s shading: raster %.3f s, shading %.3f s\n",
      file.scene.camera.width, file.scene.camera.height, triangles,
      file.scene.lighting.lights.size(), render::ShadingName(file.options.shading).c_str(),
      out.raster_seconds, out.shade_seconds);
  Say(o.common,
      "Wrote %s: %s, mask.png, normals.exr/.png, Normal_gt.mat, depth.exr, albedo.exr, "
      "material.json, render.json\n",
      o.output_dir.c_str(),
      o.per_light ? ("001" + file.output.extension() +
                     " ... with filenames.txt, "
                     "light_directions.txt, light_intensities.txt" +
                     (file.scene.lighting.HasPointLights()
                          ? std::string(", light_positions.txt, camera.json, Depth_gt.mat "
                                        "(near lights: scene units as mm)")
                          : std::string()))
                        .c_str()
                  : ("image" + file.output.extension()).c_str());
}

}  // namespace

void AddRenderCommand(CLI::App& app) {
  auto o = std::make_shared<RenderCommandOptions>();
  auto* cmd = app.add_subcommand("render", "Render a scene file; --per-light writes a dataset");
  cmd->add_option("scene", o->scene_path, "Scene file (JSON)")->required();
  cmd->add_option("-o,--output", o->output_dir,
                  "Output folder: new or empty, or an earlier render output with --overwrite")
      ->required();
  cmd->add_flag("--per-light", o->per_light,
                "One image per light in the DiLiGenT layout, with light files");
  cmd->add_option("--format", o->format, "Image format")->check(CLI::IsMember({"exr", "png"}));
  cmd->add_option("--bits", o->bits, "PNG bits per channel")->check(CLI::IsMember({8, 16}));
  cmd->add_option("--encoding", o->encoding, "PNG encoding")
      ->check(CLI::IsMember({"linear", "srgb"}));
  cmd->add_option("--shading", o->shading, "Shading mode")
      ->check(CLI::IsMember({"flat", "gouraud", "phong"}));
  cmd->add_option("--supersampling", o->supersampling, "Samples per pixel side (1-8)")
      ->check(CLI::Range(1, 8));
  cmd->add_flag("--shadows", o->shadows, "Cast shadows (one shadow map per light)");
  cmd->add_option("--noise-sigma", o->noise_sigma, "Gaussian noise sigma")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", o->seed, "Noise seed")->check(CLI::NonNegativeNumber);
  AddOverwriteOption(cmd, o->common);
  AddThreadsOption(cmd, o->common);
  AddMemoryOption(cmd, o->common);
  AddReportOptions(cmd, o->common);
  cmd->callback([o] { RunRender(*o); });
}

}  // namespace iphong::cli
