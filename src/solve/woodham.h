// Woodham's Lambertian photometric stereo (1980), the `lambert` result and the baseline every
// other estimate must beat: per pixel, the least-squares b = kd·N of y_j = L_j·b over the
// luminance of y_j = (I_j − Ia⊙ka)/E_j, after dropping the darkest `discard_dark` and brightest
// `discard_bright` fractions of the pixel's observations (shadows, highlights). Camera frame.
// Clipped observations (a channel at or above the pixel's PixelSaturation level) say only "at
// least this bright" and are left out before the ranking, as in every other fit; a pixel with
// fewer than three unclipped observations is solved on all of them (nothing else would give it a
// normal).
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "solve/internal.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

struct WoodhamSettings {
  double discard_dark = 0.3;
  double discard_bright = 0.1;
  double saturation = 0.995;           // NormalOptions::saturation (PixelSaturation)
  Vec3d ambient_term = Vec3d::Zero();  // Ia ⊙ ka, subtracted from every image
};

// (LᵀL)⁻¹Lᵀ of all lights (3 × K), or empty when the lights are degenerate: Woodham without a
// selection is one product per pixel.
Eigen::Matrix3Xd WoodhamPseudoInverse(const PhotometricData& data);

// Pixel p's normal and RGB albedo (over the kept observations lit under the normal); with
// `with_residual` also the RMS residual of the Lambertian model through the shared model.
// `order` and `lights` (what the pixel sees: per pixel for near lights, when pinv is unused) are
// the caller's buffers.
internal::PixelSolution Woodham(const PhotometricData& data, std::size_t p,
                                const WoodhamSettings& settings, const Eigen::Matrix3Xd& pinv,
                                std::vector<std::pair<double, int>>& order, PixelLights& lights,
                                bool with_residual);

}  // namespace iphong::solve
