// Pieces of normal recovery shared by its first pass (normals.cc) and its refining passes
// (refine_normals.cc); not part of the public interface.
#pragma once

#include <vector>

#include "solve/internal.h"
#include "solve/normals.h"
#include "solve/pixel_fit.h"
#include "solve/woodham.h"

namespace iphong::solve::internal {

WoodhamSettings WoodhamOf(const NormalOptions& o);
PixelFitSettings FitSettingsOf(const NormalOptions& o);
// The fit's settings for the pixels of a plan: with the object's ks prior where it chose one.
PixelFitSettings PlanFitSettings(const NormalPlan& plan);
// Throws std::invalid_argument for invalid data or options, or fewer than 3 images.
void CheckInputs(const PhotometricData& data, const NormalOptions& options);

// The result's images and counts from every pixel's solution (in data's masked order); `won`
// (per pixel: 1 specular, 0 Lambert) fills model_map when per_pixel_map.
void AssembleNormals(const PhotometricData& data, const NormalOptions& o,
                     const std::vector<PixelSolution>& solutions,
                     const std::vector<signed char>& won, bool per_pixel_map, NormalResult& result);

}  // namespace iphong::solve::internal
