#include "io/dataset.h"

#include <matio.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/parallel.h"
#include "io/json_reader.h"
#include "io/staging.h"
#include "io/text_file.h"
#include "io/visualize.h"

namespace iphong::io {
namespace fs = std::filesystem;
namespace {

[[noreturn]] void Fail(const fs::path& file, const std::string& message, int line = 0) {
  throw std::runtime_error(file.string() + (line > 0 ? ":" + std::to_string(line) : "") + ": " +
                           message);
}

// Non-empty lines of a text file, with their line numbers.
std::vector<std::pair<int, std::string>> ReadLines(const fs::path& path) {
  std::ifstream file(path);
  if (!file) Fail(path, "cannot open");
  std::vector<std::pair<int, std::string>> lines;
  std::string line;
  for (int number = 1; std::getline(file, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    lines.emplace_back(number, line);
  }
  return lines;
}

std::vector<Vec3d> ReadTriples(const fs::path& path, std::size_t expected) {
  const auto lines = ReadLines(path);
  std::vector<Vec3d> triples;
  for (const auto& [number, line] : lines) {
    // strtod, unlike operator>>, reads "nan" and "inf", so they get their own message.
    Vec3d v;
    const char* p = line.c_str();
    int count = 0;
    for (; count < 4; ++count) {
      char* end = nullptr;
      const double value = std::strtod(p, &end);
      if (end == p) break;
      if (count < 3) v[count] = value;
      p = end;
    }
    if (count != 3 || std::string(p).find_first_not_of(" \t") != std::string::npos) {
      Fail(path, "expected 3 numbers, got '" + line + "'", number);
    }
    if (!v.allFinite()) Fail(path, "not a finite number", number);
    triples.push_back(v);
  }
  if (triples.size() != expected) {
    Fail(path, "has " + std::to_string(triples.size()) + " lines for " + std::to_string(expected) +
                   " images in filenames.txt");
  }
  return triples;
}

ImageF ToRgb(ImageF image) {
  if (image.channels == 3) return image;
  ImageF rgb(image.width, image.height, 3);
  for (std::size_t p = 0; p < image.pixel_count(); ++p) {
    for (int c = 0; c < 3; ++c) {
      rgb.pixels[3 * p + c] = image.pixels[p * image.channels + (image.channels >= 3 ? c : 0)];
    }
  }
  return rgb;
}

ImageF ReadNormalText(const fs::path& path, int width, int height) {
  const auto lines = ReadLines(path);
  if (lines.size() != static_cast<std::size_t>(width) * height) {
    Fail(path, "has " + std::to_string(lines.size()) + " lines, expected " +
                   std::to_string(width * height) + " (width x height)");
  }
  ImageF normals(width, height, 3);
  for (std::size_t p = 0; p < lines.size(); ++p) {
    std::istringstream in(lines[p].second);
    double n[3];
    if (!(in >> n[0] >> n[1] >> n[2])) Fail(path, "expected 3 numbers", lines[p].first);
    for (int c = 0; c < 3; ++c) normals.pixels[3 * p + c] = static_cast<float>(n[c]);
  }
  return normals;
}

DatasetMaterial ParseMaterialJson(const fs::path& path) {
  const nlohmann::json document = JsonReader::Parse(ReadTextFile(path.string()), path.string());
  const JsonReader j(document, path.string());
  j.OnlyKeys({"model", "ambient", "ka", "kd", "ks", "shininess", "comment"});
  DatasetMaterial m;
  try {
    m.model = reflectance::ParseLobe(j.String("model", "phong"));
  } catch (const std::invalid_argument& e) {
    j.Field("model").Fail(e.what());
  }
  m.ambient = j.Rgb("ambient", Vec3d::Ones());
  m.kd_known = j.Has("kd");
  reflectance::Material unknown;  // ka, ks 0, shininess 1; kd only a placeholder when absent
  unknown.kd = Vec3d::Ones();
  m.material = ReadMaterialCoefficients(j, unknown);
  if ((m.ambient.array() < 0).any()) j.Field("ambient").Fail("must be >= 0");
  return m;
}

std::string Triples(const std::vector<Vec3d>& values) {
  std::string text;
  char line[128];
  for (const Vec3d& v : values) {
    std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", v[0], v[1], v[2]);
    text += line;
  }
  return text;
}

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

// Datasets that say their integer images are sRGB-encoded (render.json) are linearized.
bool DatasetIsSrgb(const fs::path& dir) {
  if (!fs::exists(dir / "render.json")) return false;
  const std::string path = (dir / "render.json").string();
  return JsonReader::Parse(ReadTextFile(path), path).value("encoding", "linear") == "srgb";
}

}  // namespace

void WriteNormalMat(const std::string& path, const std::string& variable, const ImageF& normals) {
  const std::size_t h = normals.height, w = normals.width;
  std::vector<double> data(h * w * 3);
  for (std::size_t r = 0; r < h; ++r)
    for (std::size_t c = 0; c < w; ++c)
      for (std::size_t k = 0; k < 3; ++k)
        data[r + h * (c + w * k)] = normals.pixels[3 * (r * w + c) + k];  // MATLAB: column-major
  WriteFileAtomically(path, [&](const std::string& temp) -> std::string {
    mat_t* mat = Mat_CreateVer(temp.c_str(), nullptr, MAT_FT_MAT5);
    if (mat == nullptr) return "cannot create the MATLAB file";
    std::size_t dims[3] = {h, w, 3};
    matvar_t* var =
        Mat_VarCreate(variable.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 3, dims, data.data(), 0);
    const bool ok = var != nullptr && Mat_VarWrite(mat, var, MAT_COMPRESSION_ZLIB) == 0;
    if (var) Mat_VarFree(var);
    Mat_Close(mat);
    return ok ? "" : "cannot write variable " + variable;
  });
}

ImageF ReadNormalMat(const std::string& path, const std::string& variable) {
  mat_t* mat = Mat_Open(path.c_str(), MAT_ACC_RDONLY);
  if (mat == nullptr) Fail(path, "not a MATLAB file matio can read");
  matvar_t* var = Mat_VarRead(mat, variable.c_str());
  Mat_Close(mat);
  if (var == nullptr) Fail(path, "has no variable " + variable);
  struct Free {
    matvar_t* v;
    ~Free() { Mat_VarFree(v); }
  } free_var{var};
  if (var->rank != 3 || var->dims[2] != 3 || var->isComplex) {
    Fail(path, variable + " must be a real H x W x 3 array");
  }
  const std::size_t h = var->dims[0], w = var->dims[1];
  ImageF normals(static_cast<int>(w), static_cast<int>(h), 3);
  auto value = [&](std::size_t i) -> double {
    if (var->class_type == MAT_C_DOUBLE) return static_cast<const double*>(var->data)[i];
    if (var->class_type == MAT_C_SINGLE) return static_cast<const float*>(var->data)[i];
    Fail(path, variable + " must be double or single");
  };
  for (std::size_t r = 0; r < h; ++r)
    for (std::size_t c = 0; c < w; ++c)
      for (std::size_t k = 0; k < 3; ++k)
        normals.pixels[3 * (r * w + c) + k] = static_cast<float>(value(r + h * (c + w * k)));
  return normals;
}

Dataset LoadDataset(const std::string& directory, const DatasetLoadOptions& options) {
  const fs::path dir(directory);
  if (!fs::is_directory(dir)) Fail(dir, "not a directory");
  Dataset d;
  d.directory = directory;
  for (const auto& [number, line] : ReadLines(dir / "filenames.txt")) {
    const auto begin = line.find_first_not_of(" \t"), end = line.find_last_not_of(" \t");
    d.filenames.push_back(line.substr(begin, end - begin + 1));
  }
  if (d.filenames.empty()) Fail(dir / "filenames.txt", "lists no images");
  const std::size_t k = d.filenames.size();

  d.light_directions = ReadTriples(dir / "light_directions.txt", k);
  for (std::size_t i = 0; i < k; ++i) {
    const double norm = d.light_directions[i].norm();
    if (!(norm > 1e-9)) {
      Fail(dir / "light_directions.txt", "zero light direction", static_cast<int>(i + 1));
    }
    if (std::abs(norm - 1) > 1e-3) {
      d.warnings.push_back("light_directions.txt: direction " + std::to_string(i + 1) +
                           " has length " + std::to_string(norm) + "; normalized");
    }
    d.light_directions[i] /= norm;
  }
  if (fs::exists(dir / "light_intensities.txt")) {
    d.light_intensities = ReadTriples(dir / "light_intensities.txt", k);
    for (std::size_t i = 0; i < k; ++i) {
      if (!(d.light_intensities[i].array() > 0).all()) {
        Fail(dir / "light_intensities.txt", "light intensities must be > 0",
             static_cast<int>(i + 1));
      }
    }
  } else {
    d.light_intensities.assign(k, Vec3d::Ones());
  }
  if (fs::exists(dir / "material.json")) d.material = ParseMaterialJson(dir / "material.json");

  if (options.load_images) {
    d.images.resize(k);
    std::vector<std::string> errors(k);
    ParallelFor(0, k, 1, options.threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        try {
          d.images[i] = ToRgb(ReadImage((dir / d.filenames[i]).string()));
        } catch (const std::exception& ex) {
          errors[i] = ex.what();
        }
      }
    });
    for (const std::string& error : errors)
      if (!error.empty()) throw std::runtime_error(error);
    if (DatasetIsSrgb(dir)) {
      for (ImageF& image : d.images)
        for (float& v : image.pixels) v = SrgbToLinear(v);
    }
    for (std::size_t i = 1; i < k; ++i) {
      if (d.images[i].width != d.images[0].width || d.images[i].height != d.images[0].height) {
        Fail(dir / d.filenames[i], "is " + std::to_string(d.images[i].width) + "x" +
                                       std::to_string(d.images[i].height) + ", but " +
                                       d.filenames[0] + " is " + std::to_string(d.images[0].width) +
                                       "x" + std::to_string(d.images[0].height));
      }
    }
  }
  const int width = d.images.empty() ? 0 : d.images[0].width;
  const int height = d.images.empty() ? 0 : d.images[0].height;

  if (fs::exists(dir / "mask.png")) {
    const ImageF m = ReadImage((dir / "mask.png").string());
    if (!d.images.empty() && (m.width != width || m.height != height)) {
      Fail(dir / "mask.png", "is " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                                 ", the images are " + std::to_string(width) + "x" +
                                 std::to_string(height));
    }
    d.mask = Mask(m.width, m.height, false);
    for (std::size_t p = 0; p < m.pixel_count(); ++p) {
      for (int c = 0; c < std::min(m.channels, 3); ++c) {
        if (m.pixels[p * m.channels + c] > 0) d.mask.inside[p] = 1;
      }
    }
  } else {
    d.mask = Mask(width, height, true);
  }

  if (options.load_ground_truth) {
    if (fs::exists(dir / "Normal_gt.mat")) {
      d.normal_gt = ReadNormalMat((dir / "Normal_gt.mat").string(), "Normal_gt");
    } else if (fs::exists(dir / "normal.txt") && d.mask.width > 0) {
      d.normal_gt = ReadNormalText(dir / "normal.txt", d.mask.width, d.mask.height);
    }
    if (!d.normal_gt.pixels.empty() &&
        (d.normal_gt.width != d.mask.width || d.normal_gt.height != d.mask.height)) {
      Fail(dir / "Normal_gt.mat", "ground truth size differs from the images");
    }
  }
  return d;
}

void WriteRenderOutput(const std::string& directory, const render::Scene& scene,
                       const render::RenderOptions& options, const render::RenderOutput& output,
                       const OutputSettings& settings, bool per_light) {
  if (per_light) {
    for (std::size_t j = 0; j < scene.lighting.lights.size(); ++j) {
      if (scene.lighting.lights[j].type != reflectance::LightType::kDirectional) {
        throw std::runtime_error("light " + std::to_string(j) +
                                 " is a point light; per-light datasets (DiLiGenT layout) need "
                                 "directional lights");
      }
    }
  }
  StagingDirectory staging(directory);
  {
    const std::string ext = settings.extension();
    const WriteOptions image_options = settings.write_options();
    if (per_light) {
      std::string names;
      std::vector<Vec3d> directions, intensities;
      const int digits = std::max<int>(3, std::to_string(output.per_light.size()).size());
      for (std::size_t j = 0; j < output.per_light.size(); ++j) {
        std::string number = std::to_string(j + 1);
        number.insert(0, digits - number.size(), '0');
        WriteImage(staging.file(number + ext), output.per_light[j], image_options);
        names += number + ext + "\n";
        directions.push_back(scene.lighting.lights[j].direction_cam);
        intensities.push_back(scene.lighting.lights[j].diffuse_intensity);
      }
      WriteTextFile(staging.file("filenames.txt"), names);
      WriteTextFile(staging.file("light_directions.txt"), Triples(directions));
      WriteTextFile(staging.file("light_intensities.txt"), Triples(intensities));
    } else {
      WriteImage(staging.file("image" + ext), output.image, image_options);
    }
    WriteImage(staging.file("mask.png"), MaskImage(output.mask), {8, Encoding::kLinear});
    WriteImage(staging.file("normals.exr"), output.normal_cam);
    WriteImage(staging.file("normals.png"), NormalMapPicture(output.normal_cam, output.mask),
               {16, Encoding::kLinear});
    WriteImage(staging.file("depth.exr"), output.depth);
    WriteImage(staging.file("albedo.exr"), output.albedo);
    WriteNormalMat(staging.file("Normal_gt.mat"), "Normal_gt", output.normal_cam);
    WriteTextFile(staging.file("material.json"), MaterialJson(scene, options).dump(2) + "\n");
    nlohmann::json meta;
    meta["generator"] = "iphong render";
    meta["images"] = per_light ? output.per_light.size() : 1;
    meta["format"] = settings.format;
    meta["bits"] = settings.format == "exr" ? 32 : settings.bits;
    meta["encoding"] =
        settings.format == "exr" || settings.encoding == Encoding::kLinear ? "linear" : "srgb";
    meta["shading"] = render::ShadingName(options.shading);
    meta["camera"] =
        scene.camera.type == geometry::CameraType::kOrthographic ? "orthographic" : "perspective";
    meta["depth"] = "distance along the view axis in scene units; 0 outside the mask";
    meta["frame"] = "camera frame: x right, y up, z toward the viewer; row 0 at the top";
    meta["supersampling"] = options.supersampling;
    meta["shadows"] = options.shadows;
    meta["noise"] = {{"gaussian_sigma", options.noise.gaussian_sigma},
                     {"shot_photons", options.noise.shot_photons},
                     {"quantization_bits", options.noise.quantization_bits},
                     {"seed", options.noise.seed}};
    WriteTextFile(staging.file("render.json"), meta.dump(2) + "\n");
  }
  staging.Commit();
}

}  // namespace iphong::io

namespace iphong::io {

ObservationSet LoadObservations(const std::string& directory, const DatasetLoadOptions& options) {
  const fs::path dir(directory);
  DatasetLoadOptions meta_options = options;
  meta_options.load_images = false;
  ObservationSet set;
  Dataset& d = set.dataset;
  d = LoadDataset(directory, meta_options);
  const std::size_t k = d.filenames.size();
  if (d.mask.width == 0) {  // no mask.png: the whole image, sized by the first image
    const ImageF first = ReadImage((dir / d.filenames[0]).string());
    d.mask = Mask(first.width, first.height, true);
  }
  const int w = d.mask.width, h = d.mask.height;
  solve::PhotometricData& data = set.observations;
  data = solve::ObservationLayout(w, h, d.mask, d.light_directions, d.light_intensities);
  const bool srgb = DatasetIsSrgb(dir);
  std::vector<std::string> errors(k);
  ParallelFor(0, k, 1, options.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t j = b; j < e; ++j) {
      const std::string path = (dir / d.filenames[j]).string();
      try {
        ImageF image = ToRgb(ReadImage(path));
        if (image.width != w || image.height != h) {
          errors[j] = path + ": is " + std::to_string(image.width) + "x" +
                      std::to_string(image.height) + ", but the mask is " + std::to_string(w) +
                      "x" + std::to_string(h);
          continue;
        }
        if (srgb)
          for (float& v : image.pixels) v = SrgbToLinear(v);
        if (auto m = solve::GatherImage(data, static_cast<int>(j), image.pixels.data());
            !m.empty()) {
          errors[j] = path + ": " + m;
        }
      } catch (const std::exception& ex) {
        errors[j] = ex.what();
      }
    }
  });
  for (const std::string& error : errors)
    if (!error.empty()) throw std::runtime_error(error);
  if (auto m = data.Validate(); !m.empty()) throw std::runtime_error(directory + ": " + m);
  return set;
}

}  // namespace iphong::io
