// Normals from one or two images (seed 003's inverse section).
//
// With one light, a pixel's shading fixes only N·L: the normals that explain it form a cone
// around L (for a cylinder profile, two mirror solutions; seed 003's example). With two lights,
// two cones meet in (at most) two normals, more near a highlight. The ambiguity is resolved
// globally: one Ceres problem over all masked pixels with the data term of the shared model
// (known, uniform coefficients), smoothness between neighbours, integrability of the implied
// gradient field, occluding-boundary priors (where the mask ends inside the image the normal is
// perpendicular to the view and points outward, along the outline's normal) and visibility
// (nz ≥ 0).
// It is solved coarse to fine on a pyramid of the observations (pyramid.h), each level's weights
// scaled so that it poses the fine level's problem at its own resolution. On the coarsest level
// the priors alone first inflate the silhouette into a smooth "balloon"; every level then starts
// each pixel on the branch its data allow nearest that guess (the balloon, or the coarser
// level's answer) before the full solve, so no start sits on a wrong branch beside a highlight.
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
  // Integrability is what a surface must satisfy; smoothness is only a preference, and a
  // curved surface pays for it, so it is the weaker: where one light leaves a pixel a cone of
  // normals, integrability and the data fix it, and smoothness decides only what nothing else
  // does (no light). The pairs measured: docs/guides/normals.md.
  double smoothness_weight = 0.2;
  double integrability_weight = 1.0;
  double boundary_weight = 2.0;
  int max_iterations = 200;  // per pyramid level
  int threads = 0;
  // Called from the solving thread after each iteration with the fraction of the run done: the
  // pyramid's levels in proportion to their pixels (the priors' stage on the coarsest first),
  // each over the iterations a level typically takes.
  std::function<void(double)> progress;

  std::string Validate() const;
};

// Memory of EstimateNormalsFewImages per masked pixel, for callers to check before the solve: it
// keeps its observation pyramid, the candidate search's answers and the sparse system of every
// level (peak resident memory of a sphere from one image: 280 MB at 37 k pixels, 680 MB at 149 k,
// 2.3 GB at 595 k: 3.7 KB a pixel). Unchecked, a 12-megapixel photo needs some 45 GB.
constexpr double kFewImageBytesPerPixel = 4000;

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
