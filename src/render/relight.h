// Relighting a capture: the shared model (reflectance/phong.h) evaluated at every pixel of the
// maps photometric stereo recovers, under lights of the user's choosing. What RTI users do with a
// capture, and what the viewer (io/viewer.h) does in a WebGL shader.
//
//   I = exposure · (a + Σ_lights E ⊙ (kd · max(N·L, 0) + s · ks · lobe)),   V = (0, 0, 1),
// with a = Ia⊙ka the ambient term, kd and (optionally) ks per pixel, s the specular scale.
// Frame: SPEC.md's camera frame; row 0 is the top row.
#pragma once

#include <string>
#include <vector>

#include "core/types.h"
#include "reflectance/lighting.h"
#include "reflectance/phong.h"

namespace iphong::render {

struct RelightInput {
  const ImageF* normals_cam = nullptr;  // 3 channels; a zero (or non-finite) normal: no surface
  const ImageF* albedo = nullptr;       // kd, 3 channels, the normals' size
  const ImageF* specular = nullptr;     // ks per pixel (3 channels), or nullptr: `ks` below
  reflectance::Lobe lobe = reflectance::Lobe::kLambert;
  Vec3d ambient_term = Vec3d::Zero();  // Ia⊙ka
  Vec3d ks = Vec3d::Zero();
  double shininess = 1;
  double specular_scale = 1;  // multiplies ks (the viewer's slider)
  double exposure = 1;
  std::vector<reflectance::Light> lights;  // directional
  int threads = 0;

  std::string Validate() const;  // "" or what is wrong (sizes, channels, values, lights)
};

// Linear RGB, the normals' size; 0 where there is no surface or no albedo. Throws
// std::invalid_argument with Validate's message.
ImageF Relight(const RelightInput& input);

// Pixels with a surface (a finite, non-zero normal) and those of them some light reaches
// (N·L > 0). A light given the way light travels (toward the surface) reaches only the few
// silhouette normals that tilt past the view.
struct RelightCoverage {
  std::size_t surface = 0, lit = 0;
};
RelightCoverage LitPixels(const RelightInput& input);
// "" when the lights reach more than 1 % of the pixels with a surface (the silhouette's few
// normals that tilt past the view see any light behind); otherwise what a user is told: the
// lights are behind the surface, and which way a light direction points.
std::string LightsBehindNote(const RelightInput& input);

}  // namespace iphong::render
