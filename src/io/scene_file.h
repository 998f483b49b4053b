// Scene files (JSON) for the renderer.
//
//   {"width": 256, "height": 256,
//    "camera": {"type": "orthographic", "extent": 2.0},          // or perspective: fov_deg,
//    distance "ambient": [1, 1, 1], "lights": [{"type": "directional", "direction": [0.3, 0.4,
//    0.866], "intensity": [1, 1, 1]},
//               {"type": "point", "position": [0, 2, 3], "intensity": 5, "falloff": true},
//               {"type": "ring", "count": 12, "elevation_deg": 45, "intensity": 1},
//               {"type": "hemisphere", "count": 96, "min_elevation_deg": 30}],
//    "objects": [{"shape": "sphere", "center": [0, 0, 0], "radius": 0.8, "subdivisions": 6,
//                 "material": "jade" | {"ka": .., "kd": .., "ks": .., "shininess": ..,
//                                       "preset": "jade"},
//                 "albedo_texture": "wood.png", "transform": {"translate": [..], "rotate_deg":
//                 [rx, ry, rz], "scale": s | [sx, sy, sz]}}],
//    "shading": "phong", "model": "phong", "shadows": false, "supersampling": 1,
//    "noise": {"gaussian_sigma": 0, "shot_photons": 0, "quantization_bits": 0, "seed": 1},
//    "output": {"format": "exr" | "png", "bits": 16, "encoding": "linear" | "srgb"}}
//
// Shapes: sphere (center, radius, subdivisions), cylinder (center, radius, height, segments,
// capped), torus (center, ring_radius, tube_radius, ring_segments, tube_segments), plane (center,
// size, divisions), box (center, size [3]), heightfield (center, size [2], resolution [2],
// function "gaussian" with amplitude, sigma, ripple_amplitude, ripple_wavelength, or image +
// scale), mesh (path to OBJ/PLY/OFF/STL, crease_angle_deg, use_file_normals). Paths are relative to
// the scene file's folder. Every error names the file and the field.
#pragma once

#include <string>
#include <vector>

#include "core/resources.h"

#include "io/image_io.h"
#include "render/renderer.h"

namespace iphong::io {

struct OutputSettings {
  std::string format = "exr";  // "exr" (float, linear) or "png" (8/16-bit)
  int bits = 16;
  Encoding encoding = Encoding::kLinear;

  std::string extension() const { return "." + format; }
  WriteOptions write_options() const { return {bits, encoding}; }
};

struct SceneFile {
  render::Scene scene;
  render::RenderOptions options;
  OutputSettings output;
  // The files the scene reads (meshes, height images, textures), resolved: with the scene file,
  // a render's inputs, which its output folder may not hold.
  std::vector<std::string> inputs;
};

// The meshes each shape makes, and the images it reads, are checked against `memory` before they
// are built or decoded (ResourceError).
SceneFile LoadSceneFile(const std::string& path, const MemoryLimit& memory = {});

class JsonReader;
// Overlays the coefficients present in `j` ("ka", "kd", "ks" as RGB or one number,
// "shininess") on `start` and validates the result; errors name the field. Scene files and
// material.json both read coefficients through this.
reflectance::Material ReadMaterialCoefficients(const JsonReader& j, reflectance::Material start);
// `source` names the document in errors; relative paths resolve against `base_dir`.
SceneFile ParseScene(const std::string& json_text, const std::string& source,
                     const std::string& base_dir, const MemoryLimit& memory = {});

}  // namespace iphong::io
