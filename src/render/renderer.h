// The forward renderer: scenes of triangle meshes shaded with the one reflection model
// (reflectance/phong.h), with exact per-pixel ground truth.
//
// Shading modes (seed 001):
//   flat     one intensity per triangle, evaluated at its centroid with the face normal;
//   gouraud  intensities evaluated at the vertices and interpolated across the triangle;
//   phong    normals interpolated (and renormalized) per pixel, the model evaluated per pixel.
// Image j of a per-light render is Ia⊙ka + light j's term (SPEC.md's dataset model); the combined
// image is Ia⊙ka + Σ_j. Images are linear and unclamped.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/resources.h"
#include "geometry/camera.h"
#include "geometry/mesh.h"
#include "reflectance/lighting.h"
#include "reflectance/material.h"

namespace iphong::render {

enum class Shading { kFlat, kGouraud, kPhong };
Shading ParseShading(const std::string& name);  // "flat", "gouraud", "phong"; throws otherwise
std::string ShadingName(Shading shading);

struct SceneObject {
  std::string name;
  geometry::TriangleMesh mesh;  // camera frame, scene units, with corner normals
  reflectance::Material material;
  ImageF albedo_texture;  // optional: kd is multiplied per channel by the texture at the uv
};

struct Scene {
  geometry::Camera camera;
  reflectance::Lighting lighting;
  std::vector<SceneObject> objects;

  std::string Validate() const;
};

struct NoiseOptions {
  double gaussian_sigma = 0;  // additive, in image units
  double shot_photons = 0;    // photons per unit intensity for Poisson noise; 0 = off
  int quantization_bits = 0;  // round to 2^bits − 1 levels on [0, 1]; 0 = off
  std::uint64_t seed = 1;

  bool enabled() const { return gaussian_sigma > 0 || shot_photons > 0 || quantization_bits > 0; }
  std::string Validate() const;
};

struct RenderOptions {
  Shading shading = Shading::kPhong;
  reflectance::ModelOptions model;
  bool renormalize_normals = true;  // seed 001; off shows the interpolation error
  bool two_sided = false;           // also draw triangles seen from behind (open meshes)
  bool shadows = false;             // cast shadows through one shadow map per light
  int shadow_map_size = 2048;
  double shadow_bias_texels = 1.5;
  int supersampling = 1;  // s×s samples per pixel, box-filtered
  NoiseOptions noise;
  int threads = 0;     // 0 = all cores
  MemoryLimit memory;  // Render refuses (ResourceError) what would not fit
  // Called from the calling thread with the fraction done (shadow maps, then one image per
  // light set), for long renders' progress.
  std::function<void(double)> progress;

  std::string Validate() const;
};

struct RenderOutput {
  ImageF image;                   // all lights
  std::vector<ImageF> per_light;  // one per light when asked for
  ImageF normal_cam;              // ground truth unit normals, 0 outside the mask
  ImageF depth;                   // 1 channel: distance along the view axis, 0 outside
  ImageF albedo;                  // kd at each pixel (texture applied), 0 outside
  Mask mask;                      // pixels whose centre (majority of samples) sees a surface
  double raster_seconds = 0;
  double shade_seconds = 0;
};

// Throws std::invalid_argument with a one-line message for an invalid scene or options, and
// ResourceError when EstimateRenderBytes exceeds options.memory.
RenderOutput Render(const Scene& scene, const RenderOptions& options, bool per_light);

// Why a render whose mask is empty shows nothing, as a sentence: every face in view seen from
// behind (one more render drawing both sides finds it: a mesh wound clockwise as the camera sees
// it, or an object turned away), every face without area, or every object outside the view.
std::string NothingVisibleReason(const Scene& scene, const RenderOptions& options);

// The memory Render allocates: the G-buffer, ground truth and one image per light set at the
// supersampled size, the downsampled results, and the shadow maps.
double EstimateRenderBytes(const Scene& scene, const RenderOptions& options, bool per_light);

// Adds the noise of `options` to an image; stream `index` makes each image's noise independent.
void ApplyNoise(ImageF& image, const NoiseOptions& options, std::uint64_t index);

}  // namespace iphong::render
