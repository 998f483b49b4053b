// `iphong relight RESULT_DIR --light lx,ly,lz -o IMAGE`: the captured object under a new light,
// from the normals, albedo (and specular) maps of `iphong normals` or `iphong fit-material`; with
// --viewer, a self-contained HTML page that relights it interactively.
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/timing.h"
#include "core/version.h"
#include "io/dataset_text.h"
#include "io/files.h"
#include "io/image_io.h"
#include "io/output_folder.h"
#include "io/viewer.h"
#include "io/visualize.h"
#include "iphong/commands.h"
#include "iphong/console.h"
#include "render/preview.h"
#include "render/relight.h"

namespace iphong::cli {
namespace {

struct RelightCommandOptions {
  std::string result_dir;
  std::vector<double> lights;  // lx,ly,lz per light
  std::vector<double> intensity = {1, 1, 1};
  std::string material;
  double exposure = 0;  // 0: auto
  double specular_scale = 1;
  bool viewer = false;
  std::string output;
  CommonOptions common;
};

void RunRelight(const RelightCommandOptions& o) {
  const auto start = Clock::now();
  RequireFolder(o.result_dir);
  const std::string ext = io::LowerExtension(o.output);
  if (o.viewer ? ext != ".html" : (ext != ".png" && ext != ".exr")) {
    throw CLI::ValidationError("--output", o.viewer ? "the viewer is a page: name it .html"
                                                    : "the image is .png (sRGB) or .exr (linear)");
  }
  if (o.lights.empty() || o.lights.size() % 3 != 0) {
    throw CLI::ValidationError("--light", "takes lx,ly,lz (repeat it for more lights)");
  }
  if (o.intensity.size() != 1 && o.intensity.size() != 3) {
    throw CLI::ValidationError("--intensity", "takes one number or r,g,b");
  }
  const Vec3d intensity = o.intensity.size() == 1
                              ? Vec3d::Constant(o.intensity[0])
                              : Vec3d(o.intensity[0], o.intensity[1], o.intensity[2]);
  try {  // the intensity's own range, named by its flag (the lights' check would name --light)
    reflectance::Light::Directional(Vec3d::UnitZ(), intensity);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--intensity", e.what());
  }
  render::RelightInput input;
  for (std::size_t i = 0; i < o.lights.size(); i += 3) {
    try {
      input.lights.push_back(reflectance::Light::Directional(
          Vec3d(o.lights[i], o.lights[i + 1], o.lights[i + 2]), intensity));
    } catch (const std::invalid_argument& e) {
      throw CLI::ValidationError("--light", e.what());
    }
  }
  const MemoryLimit memory = o.common.memory();
  const std::string dir = o.result_dir;
  auto in_dir = [&](const std::string& name) {
    return (std::filesystem::path(dir) / name).string();
  };
  for (const char* required : {"normals.exr", "albedo.exr"}) {
    if (!std::filesystem::exists(in_dir(required))) {
      throw std::runtime_error(in_dir(required) +
                               ": no such file (relight reads an `iphong normals` or "
                               "`iphong fit-material` output folder)");
    }
  }
  const ImageF normals = io::ReadNormalMap(in_dir("normals.exr"), false, nullptr, memory);
  for (const std::string& w : io::CheckNormalMap(normals, nullptr, in_dir("normals.exr"))) Warn(w);
  const ImageF albedo = io::ReadImage(in_dir("albedo.exr"), memory);
  if (albedo.width != normals.width || albedo.height != normals.height || albedo.channels != 3) {
    throw std::runtime_error(in_dir("albedo.exr") + ": is " +
                             SizeText(albedo.width, albedo.height) + " with " +
                             std::to_string(albedo.channels) + " channels; the normals are " +
                             SizeText(normals.width, normals.height) + " with 3");
  }
  // The material: --material, else the folder's material.json; without either, Lambertian.
  const std::string material_path = !o.material.empty() ? o.material
                                    : std::filesystem::exists(in_dir("material.json"))
                                        ? in_dir("material.json")
                                        : "";
  ImageF specular;
  std::string described = "Lambertian (no material.json)";
  if (!material_path.empty()) {
    const io::DatasetMaterial m =
        io::ParseMaterialJson(io::ReadTextFile(material_path), material_path);
    input.lobe = m.model;
    input.ambient_term = m.ambient.cwiseProduct(m.material.ka);
    input.ks = m.material.ks;
    input.shininess = m.material.shininess;
    described = reflectance::LobeName(m.model) + " from " + material_path;
    // `iphong normals` estimates ks per pixel: its map, unless a material is named.
    if (o.material.empty() && std::filesystem::exists(in_dir("specular.exr")) &&
        m.model != reflectance::Lobe::kLambert) {
      specular = io::ReadImage(in_dir("specular.exr"), memory);
      if (specular.width != normals.width || specular.height != normals.height ||
          specular.channels != 3) {
        throw std::runtime_error(in_dir("specular.exr") + ": is " +
                                 SizeText(specular.width, specular.height) + ", the normals " +
                                 SizeText(normals.width, normals.height));
      }
      input.specular = &specular;
      described += " with ks per pixel (specular.exr)";
    }
  }
  input.normals_cam = &normals;
  input.albedo = &albedo;
  // Auto exposure: the 99th percentile of kd at 0.8 (render::AlbedoDisplayScale), so a light
  // from the camera shows the surface as bright as the albedo picture; albedos absorb the
  // capture's light intensities and have no scale of their own.
  input.exposure = o.exposure > 0 ? o.exposure : render::AlbedoDisplayScale(albedo);
  input.specular_scale = o.specular_scale;
  input.threads = o.common.threads;
  if (std::string m = input.Validate(); !m.empty()) throw std::runtime_error(dir + ": " + m);

  const std::vector<std::string> inputs = {dir, o.material};
  if (o.viewer) {
    const std::string page = io::ViewerPage(input, std::filesystem::path(dir).filename().string());
    io::WriteSingleOutputFile("relight", o.output, o.common.overwrite, inputs,
                              [&](const std::string& temp) { io::WriteTextFile(temp, page); });
  } else {
    // A light given as the direction light travels (toward the surface) reaches no pixel: the
    // image is black, or the ambient term alone, which looks like a bad result, not a bad flag.
    if (const std::string note = render::LightsBehindNote(input); !note.empty()) {
      Warn("--light: " + note);
    }
    const ImageF image = render::Relight(input);
    io::WriteSingleOutputFile("relight", o.output, o.common.overwrite, inputs,
                              [&](const std::string& temp) {
                                if (ext == ".png") {
                                  io::WriteImage(temp, image, {8, io::Encoding::kSrgb});
                                } else {
                                  io::WriteImage(temp, image);
                                }
                              });
  }
  const double seconds = SecondsSince(start);
  nlohmann::json lights = nlohmann::json::array();
  for (const auto& light : input.lights) {
    const Vec3d& d = light.direction_cam;
    lights.push_back({d.x(), d.y(), d.z()});
  }
  PrintJson(o.common, nlohmann::json{{"iphong_version", kVersion},
                                     {"result_dir", dir},
                                     {"output", o.output},
                                     {"viewer", o.viewer},
                                     {"shading", described},
                                     {"light_directions", lights},
                                     {"exposure", input.exposure},
                                     {"seconds", seconds}}
                          .dump(2));
  Say(o.common, "Relit %s (%s) under %zu light(s), exposure %.4g: wrote %s (%.2f s)\n", dir.c_str(),
      described.c_str(), input.lights.size(), input.exposure, o.output.c_str(), seconds);
}

}  // namespace

void AddRelightCommand(CLI::App& app) {
  auto o = std::make_shared<RelightCommandOptions>();
  auto* cmd = app.add_subcommand(
      "relight",
      "Render a capture under new lights from its normals, albedo and material (an `iphong "
      "normals` or `fit-material` output), or write an interactive WebGL viewer");
  cmd->add_option("result_dir", o->result_dir,
                  "Folder with normals.exr and albedo.exr (and material.json, specular.exr)")
      ->required();
  cmd->add_option("--light", o->lights,
                  "Light direction lx,ly,lz or lx ly lz (camera frame, toward the light; repeat "
                  "for more)")
      ->required()
      ->delimiter(',')
      // lx,ly,lz or lx ly lz: "--light 0 0 1" read one number and called the rest stray
      // arguments. Grouped in threes by RunRelight.
      ->expected(1, CLI::detail::expected_max_vector_size)
      ->allow_extra_args(true)
      // Each comma-separated piece, before conversion: "0 0 1" gets the flag's own hint.
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            double v = 0;
            if (CLI::detail::lexical_cast(text, v)) return "";
            return "takes lx,ly,lz: three numbers, separated by commas or as three arguments "
                   "(got '" +
                   text + "'; repeat the flag for more lights)";
          },
          "NUMBER"));
  cmd->add_option("--intensity", o->intensity, "Light intensity: one number, or r,g,b or r g b")
      ->delimiter(',')
      ->expected(1, 3)
      ->capture_default_str();
  cmd->add_option("--material", o->material,
                  "material.json to shade with (default: the folder's; e.g. a fit-material "
                  "result)");
  cmd->add_option("--exposure", o->exposure,
                  "Multiplies the image (default: the 99th percentile of the albedo at 0.8)")
      ->check(Positive());
  cmd->add_option("--specular", o->specular_scale, "Multiplies ks")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  cmd->add_flag("--viewer", o->viewer,
                "Write a self-contained HTML page (-o PAGE.html) that relights interactively");
  cmd->add_option("-o,--output", o->output,
                  "Output image (.png sRGB, .exr linear) or, with --viewer, page (.html); a new "
                  "file, or --overwrite")
      ->required();
  cmd->add_flag("--overwrite", o->common.overwrite, "Replace an existing output file");
  AddThreadsOption(cmd, o->common);
  AddMemoryOption(cmd, o->common);
  AddReportOptions(cmd, o->common);
  cmd->callback([o] { RunRelight(*o); });
}

}  // namespace iphong::cli
