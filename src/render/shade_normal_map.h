// Deferred shading: the reflection model evaluated at every masked pixel of a surface map.
// This is the per-pixel path of the renderer; the scan-line rasterizer fills the same
// SurfaceMap from meshes.
#pragma once

#include "geometry/analytic.h"
#include "geometry/camera.h"
#include "reflectance/lighting.h"
#include "reflectance/material.h"

namespace iphong::render {

// Returns a linear, unclamped 3-channel image (0 where the mask is off). Orthographic view.
ImageF ShadeSurfaceMap(const geometry::SurfaceMap& surface, const geometry::Camera& camera,
                       const reflectance::Material& material, const reflectance::Lighting& lighting,
                       const reflectance::ModelOptions& options);

}  // namespace iphong::render
