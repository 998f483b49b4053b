// Pictures of a material fit: the specular lobe as the data show it against the fitted curve,
// and observed against predicted images.
#pragma once

#include <string>
#include <vector>

#include "core/types.h"
#include "material/fit.h"

namespace iphong::io {

// The lobe plot of seed 000: per bin of the lobe's angle (between R and V for Phong, N and H for
// Blinn-Phong) the mean of (observation − ambient − diffuse) / (E·ks) with ±2 standard errors,
// and the fitted cos(angle)^n over it. An 8-bit PNG (atomically).
void WriteLobePlot(const std::string& path, const std::vector<material::LobeBin>& bins,
                   reflectance::Lobe lobe, double shininess, const std::string& title);

// One row per light: observed | predicted | |difference| × 4, linear images shown with one
// exposure (the observed 99th percentile at 0.9), tiles at most 320 px. An 8-bit sRGB PNG.
void WriteComparisonPicture(const std::string& path, const std::vector<ImageF>& observed,
                            const std::vector<ImageF>& predicted,
                            const std::vector<std::string>& light_labels);

}  // namespace iphong::io
