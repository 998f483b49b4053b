// Normals from one or two images (seed 003's inverse section).
//
// With one light, a pixel's shading fixes only N·L: the normals that explain it form a cone
// around L (for a cylinder profile, two mirror solutions; seed 003's example). With two lights,
// two cones meet in (at most) two normals. The ambiguity is resolved globally: one Ceres problem
// over all masked pixels with the data term of the shared model (known, uniform coefficients),
// smoothness between neighbours, integrability of the implied gradient field, occluding-boundary
// priors (where the mask ends inside the image the normal is perpendicular to the view and points
// outward) and visibility (nz ≥ 0). A first stage without the data term inflates the boundary
// priors into a smooth "balloon", the starting point of the full problem.
// Frame: SPEC.md's camera frame, orthographic view V = (0, 0, 1).
#pragma once

#include <array>
#include <functional>
#include <string>

#include "reflectance/material.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

// Seed 003's cylinder profile: the two unit normals (Nx, Nz) with L·N = shading, for a light
// direction (Lx, Lz) in the profile's plane. Throws std::invalid_argument if |shading| > 1 or L
// is zero. The first solution is the one rotated from L toward +x.
std::array<Eigen::Vector2d, 2> ProfileNormals(double shading, const Eigen::Vector2d& light_xz);

struct FewImageOptions {
  reflectance::Lobe model = reflectance::Lobe::kLambert;
  reflectance::Material material;      // kd must be known (uniform albedo)
  Vec3d ambient_term = Vec3d::Zero();  // Ia ⊙ ka
  double smoothness_weight = 0.5;
  double integrability_weight = 0.2;
  double boundary_weight = 2.0;
  int max_iterations = 200;
  int threads = 0;
  // Called from the solving thread after each iteration with the fraction of the iteration
  // budget spent (the priors' stage counts a fifth): the solve may converge before 1.
  std::function<void(double)> progress;

  std::string Validate() const;
};

struct FewImageResult {
  ImageF normals;        // 3 channels, 0 outside the mask
  ImageF ambiguity_deg;  // 1 channel: angle spanned by the normals the data alone allows
  ImageF residual;       // 1 channel: RMS data residual at the solution
  int iterations = 0;
  double solve_seconds = 0;
  double final_cost = 0;
  std::string message;
};

// For 1 or 2 images. Throws std::invalid_argument on invalid input.
FewImageResult EstimateNormalsFewImages(const PhotometricData& data,
                                        const FewImageOptions& options);

}  // namespace iphong::solve
