#include "io/scene_file.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "geometry/primitives.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"
#include "io/text_file.h"

namespace iphong::io {
namespace fs = std::filesystem;
namespace {

using geometry::Camera;
using reflectance::Light;
using reflectance::Material;

constexpr double kDeg = M_PI / 180.0;

std::string Resolve(const std::string& base_dir, const std::string& path) {
  const fs::path p(path);
  return p.is_absolute() || base_dir.empty() ? path : (fs::path(base_dir) / p).string();
}

double Positive(const JsonReader& j, const std::string& key, double fallback) {
  const double v = j.Number(key, fallback);
  if (!(v > 0)) j.Field(key).Fail("expected a number > 0");
  return v;
}

int IntegerIn(const JsonReader& j, const std::string& key, int fallback, int lo, int hi) {
  const int v = j.Integer(key, fallback);
  if (v < lo || v > hi) {
    j.Field(key).Fail("expected an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
  }
  return v;
}

Material ParseMaterial(const JsonReader& j) {
  Material m;
  if (j.value().is_string()) {
    try {
      return reflectance::FindMaterialPreset(j.String()).material;
    } catch (const std::invalid_argument& e) {
      j.Fail(e.what());
    }
  }
  j.OnlyKeys({"preset", "ka", "kd", "ks", "shininess"});
  if (j.Has("preset")) m = ParseMaterial(j.Field("preset"));
  return ReadMaterialCoefficients(j, m);
}

std::vector<Light> ParseLight(const JsonReader& j) {
  const std::string type = j.String("type", "directional");
  const Vec3d intensity = j.Rgb("intensity", Vec3d::Ones());
  const Vec3d specular = j.Rgb("specular_intensity", intensity);
  try {
    if (type == "directional") {
      j.OnlyKeys({"type", "direction", "intensity", "specular_intensity"});
      return {Light::Directional(j.Field("direction").Vector3(), intensity, specular)};
    }
    if (type == "point") {
      j.OnlyKeys({"type", "position", "intensity", "specular_intensity", "falloff"});
      return {Light::Point(j.Field("position").Vector3(), intensity, specular,
                           j.Bool("falloff", true))};
    }
    if (type == "ring") {
      // `count` lights evenly around the view axis at one elevation above the image plane.
      j.OnlyKeys({"type", "count", "elevation_deg", "azimuth_offset_deg", "intensity",
                  "specular_intensity"});
      const int count = IntegerIn(j, "count", 8, 1, 100000);
      const double elevation = j.Number("elevation_deg", 45) * kDeg;
      const double offset = j.Number("azimuth_offset_deg", 0) * kDeg;
      std::vector<Light> lights;
      for (int i = 0; i < count; ++i) {
        const double az = offset + 2 * M_PI * i / count;
        lights.push_back(
            Light::Directional(Vec3d(std::cos(elevation) * std::cos(az),
                                     std::cos(elevation) * std::sin(az), std::sin(elevation)),
                               intensity, specular));
      }
      return lights;
    }
    if (type == "hemisphere") {
      // A Fibonacci spiral: `count` directions spread evenly over the cap above min elevation.
      j.OnlyKeys({"type", "count", "min_elevation_deg", "intensity", "specular_intensity"});
      const int count = IntegerIn(j, "count", 32, 1, 100000);
      const double z_min = std::sin(j.Number("min_elevation_deg", 20) * kDeg);
      const double golden = M_PI * (3 - std::sqrt(5.0));
      std::vector<Light> lights;
      for (int i = 0; i < count; ++i) {
        const double z = 1 - (1 - z_min) * (i + 0.5) / count;
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        lights.push_back(Light::Directional(
            Vec3d(r * std::cos(golden * i), r * std::sin(golden * i), z), intensity, specular));
      }
      return lights;
    }
  } catch (const std::invalid_argument& e) {
    j.Fail(e.what());
  }
  j.Field("type").Fail("unknown light type '" + type +
                       "' (expected directional, point, ring or hemisphere)");
}

Eigen::Affine3d ParseTransform(const JsonReader& object) {
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  if (object.Has("center")) t.translate(object.Field("center").Vector3());
  if (!object.Has("transform")) return t;
  const JsonReader j = object.Field("transform");
  j.OnlyKeys({"translate", "rotate_deg", "scale"});
  t.translate(j.Vector3("translate", Vec3d::Zero()));
  const Vec3d r = j.Vector3("rotate_deg", Vec3d::Zero()) * kDeg;  // about x, then y, then z
  t.rotate(Eigen::AngleAxisd(r.z(), Vec3d::UnitZ()) * Eigen::AngleAxisd(r.y(), Vec3d::UnitY()) *
           Eigen::AngleAxisd(r.x(), Vec3d::UnitX()));
  if (j.Has("scale")) {
    const Vec3d s = j.Field("scale").Rgb();  // one number or three
    if (!(s.array() != 0).all()) j.Field("scale").Fail("scale must be non-zero");
    t.scale(s);
  }
  return t;
}

render::SceneObject ParseObject(const JsonReader& j, const std::string& base_dir) {
  render::SceneObject object;
  const std::string shape = j.Field("shape").String();
  object.name = j.String("name", shape);
  std::set<std::string> keys = {"shape",          "name",      "material",
                                "albedo_texture", "transform", "center"};
  auto allow = [&](std::initializer_list<const char*> more) {
    for (const char* k : more) keys.insert(k);
  };
  try {
    if (shape == "sphere") {
      allow({"radius", "subdivisions"});
      object.mesh =
          geometry::MakeSphere(Positive(j, "radius", 1.0), IntegerIn(j, "subdivisions", 5, 0, 9));
    } else if (shape == "cylinder") {
      allow({"radius", "height", "segments", "capped"});
      object.mesh =
          geometry::MakeCylinder(Positive(j, "radius", 0.5), Positive(j, "height", 1.0),
                                 IntegerIn(j, "segments", 128, 3, 1 << 20), j.Bool("capped", true));
    } else if (shape == "torus") {
      allow({"ring_radius", "tube_radius", "ring_segments", "tube_segments"});
      object.mesh =
          geometry::MakeTorus(Positive(j, "ring_radius", 0.6), Positive(j, "tube_radius", 0.25),
                              IntegerIn(j, "ring_segments", 128, 3, 1 << 16),
                              IntegerIn(j, "tube_segments", 64, 3, 1 << 16));
    } else if (shape == "plane") {
      allow({"size", "divisions"});
      object.mesh =
          geometry::MakePlane(Positive(j, "size", 2.0), IntegerIn(j, "divisions", 1, 1, 8192));
    } else if (shape == "box") {
      allow({"size"});
      object.mesh = geometry::MakeBox(j.Vector3("size", Vec3d::Ones()));
    } else if (shape == "heightfield") {
      allow({"size", "resolution", "function", "amplitude", "sigma", "ripple_amplitude",
             "ripple_wavelength", "image", "scale"});
      double sx = 2, sy = 2;
      if (j.Has("size")) {
        const JsonReader s = j.Field("size");
        if (s.Size() != 2) s.Fail("expected [width, height]");
        sx = s.At(0).Number();
        sy = s.At(1).Number();
      }
      if (j.Has("image")) {
        ImageF heights = ReadImage(Resolve(base_dir, j.Field("image").String()));
        const double scale = j.Number("scale", 0.1);
        for (float& v : heights.pixels) v = static_cast<float>(v * scale);
        if (heights.channels > 1) {  // keep the first channel
          ImageF single(heights.width, heights.height, 1);
          for (std::size_t p = 0; p < single.pixels.size(); ++p)
            single.pixels[p] = heights.pixels[p * heights.channels];
          heights = std::move(single);
        }
        object.mesh = geometry::MakeHeightField(heights, sx, sy);
      } else {
        const std::string function = j.String("function", "gaussian");
        if (function != "gaussian") j.Field("function").Fail("expected \"gaussian\" (or image)");
        geometry::BumpRipples f;
        f.amplitude = j.Number("amplitude", f.amplitude);
        f.sigma = Positive(j, "sigma", f.sigma);
        f.ripple_amplitude = j.Number("ripple_amplitude", f.ripple_amplitude);
        f.ripple_wavelength = Positive(j, "ripple_wavelength", f.ripple_wavelength);
        int cols = 256, rows = 256;
        if (j.Has("resolution")) {
          const JsonReader r = j.Field("resolution");
          if (r.Size() != 2) r.Fail("expected [columns, rows]");
          cols = static_cast<int>(r.At(0).Number());
          rows = static_cast<int>(r.At(1).Number());
        }
        object.mesh = geometry::MakeHeightField(f, sx, sy, cols, rows);
      }
    } else if (shape == "mesh") {
      allow({"path", "crease_angle_deg", "use_file_normals"});
      MeshLoadOptions load;
      load.crease_angle_deg = j.Number("crease_angle_deg", load.crease_angle_deg);
      load.use_file_normals = j.Bool("use_file_normals", load.use_file_normals);
      object.mesh = LoadMesh(Resolve(base_dir, j.Field("path").String()), load);
    } else {
      j.Field("shape").Fail("unknown shape '" + shape +
                            "' (expected sphere, cylinder, torus, plane, box, heightfield, mesh)");
    }
  } catch (const JsonError&) {
    throw;
  } catch (const std::exception& e) {  // bad parameters, unreadable mesh or height image
    j.Fail(e.what());
  }
  j.OnlyKeys(keys);
  geometry::TransformMesh(object.mesh, ParseTransform(j));
  object.material = j.Has("material") ? ParseMaterial(j.Field("material"))
                                      : reflectance::FindMaterialPreset("plastic").material;
  if (j.Has("albedo_texture")) {
    const JsonReader texture = j.Field("albedo_texture");
    try {
      object.albedo_texture = ReadImage(Resolve(base_dir, texture.String()));
    } catch (const JsonError&) {
      throw;
    } catch (const std::exception& e) {
      texture.Fail(e.what());
    }
    if (object.mesh.uvs.empty()) j.Fail("albedo_texture needs a shape with uv coordinates");
  }
  return object;
}

Camera ParseCamera(const JsonReader& root) {
  const int width = IntegerIn(root, "width", 256, 1, 65536);
  const int height = IntegerIn(root, "height", 256, 1, 65536);
  if (!root.Has("camera")) return Camera::Orthographic(width, height, 2.0);
  const JsonReader j = root.Field("camera");
  const std::string type = j.String("type", "orthographic");
  if (type == "orthographic") {
    j.OnlyKeys({"type", "extent"});
    return Camera::Orthographic(width, height, Positive(j, "extent", 2.0));
  }
  if (type != "perspective") j.Field("type").Fail("expected orthographic or perspective");
  j.OnlyKeys({"type", "fov_deg", "distance", "fx", "fy", "cx", "cy"});
  const double distance = Positive(j, "distance", 4.0);
  Camera camera = Camera::Perspective(width, height, j.Number("fov_deg", 40), distance);
  if (j.Has("fx")) {
    camera.fx = Positive(j, "fx", 1);
    camera.fy = Positive(j, "fy", camera.fx);
    camera.cx = j.Number("cx", 0.5 * width);
    camera.cy = j.Number("cy", 0.5 * height);
  }
  if (auto m = camera.Validate(); !m.empty()) j.Fail(m);
  return camera;
}

}  // namespace

Material ReadMaterialCoefficients(const JsonReader& j, Material m) {
  m.ka = j.Rgb("ka", m.ka);
  m.kd = j.Rgb("kd", m.kd);
  m.ks = j.Rgb("ks", m.ks);
  m.shininess = j.Number("shininess", m.shininess);
  if (auto message = reflectance::ValidateMaterial(m); !message.empty()) j.Fail(message);
  return m;
}

SceneFile ParseScene(const std::string& json_text, const std::string& source,
                     const std::string& base_dir) {
  const nlohmann::json document = JsonReader::Parse(json_text, source);
  const JsonReader root(document, source);
  root.OnlyKeys({"width", "height", "camera", "ambient", "lights", "objects", "shading", "model",
                 "fast_specular", "renormalize_normals", "shadows", "shadow_map_size",
                 "supersampling", "noise", "output", "comment"});
  SceneFile file;
  file.scene.camera = ParseCamera(root);
  file.scene.lighting.ambient = root.Rgb("ambient", Vec3d::Zero());
  if ((file.scene.lighting.ambient.array() < 0).any()) root.Field("ambient").Fail("must be >= 0");
  const JsonReader lights = root.Field("lights");
  for (std::size_t i = 0; i < lights.Size(); ++i) {
    for (const Light& light : ParseLight(lights.At(i))) file.scene.lighting.lights.push_back(light);
  }
  if (file.scene.lighting.lights.empty()) lights.Fail("the scene needs at least one light");
  const JsonReader objects = root.Field("objects");
  if (objects.Size() == 0) objects.Fail("the scene needs at least one object");
  for (std::size_t i = 0; i < objects.Size(); ++i) {
    file.scene.objects.push_back(ParseObject(objects.At(i), base_dir));
  }

  render::RenderOptions& o = file.options;
  try {
    o.shading = render::ParseShading(root.String("shading", "phong"));
  } catch (const std::invalid_argument& e) {
    root.Field("shading").Fail(e.what());
  }
  try {
    o.model.lobe = reflectance::ParseLobe(root.String("model", "phong"));
  } catch (const std::invalid_argument& e) {
    root.Field("model").Fail(e.what());
  }
  if (root.Bool("fast_specular", false)) o.model.power = reflectance::PowerMode::kFastApprox;
  o.renormalize_normals = root.Bool("renormalize_normals", true);
  o.shadows = root.Bool("shadows", false);
  o.shadow_map_size = IntegerIn(root, "shadow_map_size", o.shadow_map_size, 16, 16384);
  o.supersampling = IntegerIn(root, "supersampling", 1, 1, 8);
  if (root.Has("noise")) {
    const JsonReader n = root.Field("noise");
    n.OnlyKeys({"gaussian_sigma", "shot_photons", "quantization_bits", "seed"});
    o.noise.gaussian_sigma = n.Number("gaussian_sigma", 0);
    o.noise.shot_photons = n.Number("shot_photons", 0);
    o.noise.quantization_bits = IntegerIn(n, "quantization_bits", 0, 0, 24);
    o.noise.seed = static_cast<std::uint64_t>(IntegerIn(n, "seed", 1, 0, 1 << 30));
    if (auto m = o.noise.Validate(); !m.empty()) n.Fail(m);
  }
  if (root.Has("output")) {
    const JsonReader out = root.Field("output");
    out.OnlyKeys({"format", "bits", "encoding"});
    file.output.format = out.String("format", "exr");
    if (file.output.format != "exr" && file.output.format != "png") {
      out.Field("format").Fail("expected exr or png");
    }
    file.output.bits = out.Integer("bits", 16);
    if (file.output.bits != 8 && file.output.bits != 16) out.Field("bits").Fail("expected 8 or 16");
    const std::string encoding = out.String("encoding", "linear");
    if (encoding != "linear" && encoding != "srgb") {
      out.Field("encoding").Fail("expected linear or srgb");
    }
    file.output.encoding = encoding == "srgb" ? Encoding::kSrgb : Encoding::kLinear;
  }
  if (auto m = file.scene.Validate(); !m.empty()) root.Fail(m);
  return file;
}

SceneFile LoadSceneFile(const std::string& path) {
  return ParseScene(ReadTextFile(path), path, fs::path(path).parent_path().string());
}

}  // namespace iphong::io
