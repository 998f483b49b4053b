#include "io/scene_file.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/errors.h"
#include "geometry/primitives.h"
#include "io/dataset_text.h"
#include "io/files.h"
#include "io/json_reader.h"
#include "io/mesh_io.h"

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

// Bytes a triangle costs from its construction to the rasterizer's screen coordinates and band
// lists (positions, corner normals, uvs, projected vertices): 142 measured at the peak of a
// 8.4-million-triangle plane render, rounded up.
constexpr double kBytesPerTriangle = 150;

// What parsing one scene carries along: where relative paths start, and the memory the meshes
// made so far take, checked against the limit before each is built.
struct ParseContext {
  std::string base_dir;
  MemoryLimit memory;
  double mesh_bytes = 0;
  std::vector<std::string> inputs;  // files read, resolved

  std::string Input(const std::string& path) {
    inputs.push_back(Resolve(base_dir, path));
    return inputs.back();
  }

  void Reserve(const JsonReader& j, double triangles) {
    mesh_bytes += triangles * kBytesPerTriangle;
    RequireMemory(memory, mesh_bytes,
                  j.where() + ": a mesh of " + std::to_string(static_cast<long long>(triangles)) +
                      " triangles (with the scene's other meshes)");
  }
};

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

// A preset name, or {"preset" | "file", then coefficients over it}. "file" is a material.json
// (`iphong fit-material`'s, a dataset's): its ka, kd, ks and shininess; its "ambient" and "model"
// belong to the scene ("ambient", "model"). Without kd (fitted per pixel) the scene gives one.
Material ParseMaterial(const JsonReader& j, ParseContext& context) {
  Material m;
  if (j.value().is_string()) {
    try {
      return reflectance::FindMaterialPreset(j.String()).material;
    } catch (const std::invalid_argument& e) {
      j.Fail(e.what());
    }
  }
  j.OnlyKeys({"preset", "file", "ka", "kd", "ks", "shininess"});
  if (j.Has("preset") && j.Has("file")) j.Fail("give \"preset\" or \"file\", not both");
  if (j.Has("preset")) m = ParseMaterial(j.Field("preset"), context);
  if (j.Has("file")) {
    const std::string path = context.Input(j.Field("file").String());
    const DatasetMaterial file = ParseMaterialJson(ReadTextFile(path), path);
    if (!file.kd_known && !j.Has("kd")) {
      j.Field("file").Fail(path +
                           " has no kd (it was fitted per pixel: see its albedo.exr); "
                           "add \"kd\" to the material");
    }
    m = file.material;
  }
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
      j.OnlyKeys(
          {"type", "position", "intensity", "specular_intensity", "falloff", "axis", "anisotropy"});
      Light light =
          Light::Point(j.Field("position").Vector3(), intensity, specular, j.Bool("falloff", true));
      if (j.Has("axis") || j.Has("anisotropy")) {
        // An LED (SPEC.md "Near lights"): its intensity toward a point scales by cos^μ of the
        // angle from its axis.
        const Light led = Light::Led(light.position_cam, intensity,
                                     j.Vector3("axis", Vec3d(0, 0, -1)), j.Number("anisotropy", 0));
        light.axis_cam = led.axis_cam;
        light.anisotropy = led.anisotropy;
      }
      return {light};
    }
    if (type == "point_dome" || type == "point_ring") {
      // Near-light rigs: `count` point lights (LEDs aimed at `target` when `anisotropy` > 0).
      // point_dome: on a sphere of `radius` round `center`, a Fibonacci spiral between two
      // elevations above the plane facing the camera; point_ring: on a circle of `radius` round
      // the optical axis in the plane z = `z` (a ring round the lens at z 0).
      const bool dome = type == "point_dome";
      if (dome) {
        j.OnlyKeys({"type", "count", "center", "radius", "min_elevation_deg", "max_elevation_deg",
                    "intensity", "specular_intensity", "anisotropy"});
      } else {
        j.OnlyKeys({"type", "count", "radius", "z", "target", "azimuth_offset_deg", "intensity",
                    "specular_intensity", "anisotropy"});
      }
      const int count = IntegerIn(j, "count", 24, 1, 100000);
      const double radius = j.Number("radius", 3);
      if (!(radius > 0) || !(radius < 1e12)) j.Field("radius").Fail("expected a radius > 0");
      const double mu = j.Number("anisotropy", 0);
      std::vector<Light> lights;
      if (dome) {
        const Vec3d center = j.Vector3("center", Vec3d::Zero());
        const double lo = j.Number("min_elevation_deg", 20), hi = j.Number("max_elevation_deg", 75);
        if (!(lo >= 0 && lo <= hi && hi <= 90)) {
          j.Fail("elevations must satisfy 0 <= min_elevation_deg <= max_elevation_deg <= 90");
        }
        const double golden = M_PI * (3 - std::sqrt(5.0));
        for (int i = 0; i < count; ++i) {
          const double e = (lo + (hi - lo) * (i + 0.5) / count) * kDeg;
          const Vec3d d(std::cos(e) * std::cos(golden * i), std::cos(e) * std::sin(golden * i),
                        std::sin(e));
          lights.push_back(Light::Led(center + radius * d, intensity, -d, mu));
          lights.back().specular_intensity = specular;
        }
      } else {
        const double z = j.Number("z", 0);
        const Vec3d target = j.Vector3("target", Vec3d(0, 0, z - 1));
        const double offset = j.Number("azimuth_offset_deg", 0) * kDeg;
        for (int i = 0; i < count; ++i) {
          const double a = offset + 2 * M_PI * i / count;
          const Vec3d position(radius * std::cos(a), radius * std::sin(a), z);
          const Vec3d aim = target - position;
          lights.push_back(
              Light::Led(position, intensity, aim.norm() > 0 ? aim : Vec3d(0, 0, -1), mu));
          lights.back().specular_intensity = specular;
        }
      }
      return lights;
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
                       "' (expected directional, point, ring, hemisphere, point_dome or "
                       "point_ring)");
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

render::SceneObject ParseObject(const JsonReader& j, ParseContext& context) {
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
      const double radius = Positive(j, "radius", 1.0);
      const int subdivisions = IntegerIn(j, "subdivisions", 5, 0, 9);
      context.Reserve(j, 20 * std::pow(4.0, subdivisions));
      object.mesh = geometry::MakeSphere(radius, subdivisions);
    } else if (shape == "cylinder") {
      allow({"radius", "height", "segments", "capped"});
      const double radius = Positive(j, "radius", 0.5), height = Positive(j, "height", 1.0);
      const int segments = IntegerIn(j, "segments", 128, 3, 1 << 20);
      const bool capped = j.Bool("capped", true);
      context.Reserve(j, (capped ? 4.0 : 2.0) * segments);
      object.mesh = geometry::MakeCylinder(radius, height, segments, capped);
    } else if (shape == "torus") {
      allow({"ring_radius", "tube_radius", "ring_segments", "tube_segments"});
      const double ring = Positive(j, "ring_radius", 0.6), tube = Positive(j, "tube_radius", 0.25);
      const int ring_segments = IntegerIn(j, "ring_segments", 128, 3, 1 << 16);
      const int tube_segments = IntegerIn(j, "tube_segments", 64, 3, 1 << 16);
      context.Reserve(j, 2.0 * ring_segments * tube_segments);
      object.mesh = geometry::MakeTorus(ring, tube, ring_segments, tube_segments);
    } else if (shape == "plane") {
      allow({"size", "divisions"});
      const double size = Positive(j, "size", 2.0);
      const int divisions = IntegerIn(j, "divisions", 1, 1, 8192);
      context.Reserve(j, 2.0 * divisions * divisions);
      object.mesh = geometry::MakePlane(size, divisions);
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
        const std::string path = context.Input(j.Field("image").String());
        ImageF heights = ReadImage(path, context.memory, [&](const ImageHeader& h) {
          context.Reserve(j, 2.0 * h.width * h.height);
        });
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
          cols = r.At(0).Integer();
          rows = r.At(1).Integer();
          if (cols < 2 || rows < 2 || cols > 1 << 16 || rows > 1 << 16) {
            r.Fail("expected two integers in 2..65536");
          }
        }
        context.Reserve(j, 2.0 * cols * rows);
        object.mesh = geometry::MakeHeightField(f, sx, sy, cols, rows);
      }
    } else if (shape == "mesh") {
      allow({"path", "crease_angle_deg", "use_file_normals"});
      MeshLoadOptions load;
      load.crease_angle_deg = j.Number("crease_angle_deg", load.crease_angle_deg);
      load.use_file_normals = j.Bool("use_file_normals", load.use_file_normals);
      const std::string path = context.Input(j.Field("path").String());
      // A mesh file holds at least ~12 bytes per triangle (binary STL's 50, PLY's 13).
      context.Reserve(j, static_cast<double>(RequireRegularFile(path)) / 12);
      object.mesh = LoadMesh(path, load);
    } else {
      j.Field("shape").Fail("unknown shape '" + shape +
                            "' (expected sphere, cylinder, torus, plane, box, heightfield, mesh)");
    }
  } catch (const JsonError&) {
    throw;
  } catch (const ResourceError&) {
    throw;
  } catch (const std::exception& e) {  // bad parameters, unreadable mesh or height image
    j.Fail(e.what());
  }
  j.OnlyKeys(keys);
  geometry::TransformMesh(object.mesh, ParseTransform(j));
  for (const Vec3d& p : object.mesh.positions) {
    if (!p.allFinite() || !(p.cwiseAbs().maxCoeff() < 1e15)) {
      j.Fail("coordinates beyond 1e15 scene units (size or transform too large)");
    }
  }
  object.material = j.Has("material") ? ParseMaterial(j.Field("material"), context)
                                      : reflectance::FindMaterialPreset("plastic").material;
  if (j.Has("albedo_texture")) {
    const JsonReader texture = j.Field("albedo_texture");
    try {
      object.albedo_texture = ReadImage(context.Input(texture.String()), context.memory);
    } catch (const JsonError&) {
      throw;
    } catch (const ResourceError&) {
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
  const double fov_deg = j.Number("fov_deg", 40);
  // A pinhole sees less than a half-space: at 180° the focal length is 0 and nothing is drawn.
  if (!(fov_deg > 0 && fov_deg < 180)) j.Field("fov_deg").Fail("expected a number in (0, 180)");
  Camera camera = Camera::Perspective(width, height, fov_deg, distance);
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
                     const std::string& base_dir, const MemoryLimit& memory) {
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
  ParseContext context;
  context.base_dir = base_dir;
  context.memory = memory;
  for (std::size_t i = 0; i < objects.Size(); ++i) {
    file.scene.objects.push_back(ParseObject(objects.At(i), context));
  }
  file.inputs = context.inputs;

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

SceneFile LoadSceneFile(const std::string& path, const MemoryLimit& memory) {
  return ParseScene(ReadTextFile(path), path, fs::path(path).parent_path().string(), memory);
}

}  // namespace iphong::io
