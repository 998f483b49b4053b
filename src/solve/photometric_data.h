// Observations for photometric stereo: the masked pixels of K images under K known lights,
// stored pixel-major (all of one pixel's K×3 values together) because every solver works one
// pixel at a time. Memory: K × pixels × 3 floats for the masked pixels only.
//
// Image j is modelled (SPEC.md) as  I_j = Ia⊙ka + E_j ⊙ (kd·(N·L_j) + ks·lobe_j),  E_j the RGB
// intensity of light j, L_j its unit direction (surface → light, camera frame), V = (0, 0, 1).
//
// Near lights (SPEC.md "Near lights"): with `point_lights`, light j is a point light (an LED:
// position, intensity Φ_j, axis and anisotropy) and each pixel sees it from its own surface point
// X = points_cam[p]: L_j(X) and E_j(X) = Φ_j·(a·(X − S)/|X − S|)^μ/|X − S|² come from
// reflectance::LightAt, and a perspective view has V(X) = −X/|X| (the eye at the origin). The
// shared light_directions and light_intensities are then the lights as seen from one reference
// point of the object, which is all the global search's tables (search.h) use: a start.
#pragma once

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "core/types.h"
#include "reflectance/lighting.h"

namespace iphong::solve {

// Light intensities are relative; each channel lies in [1e-30, 1e30], so that observations
// divided by them stay finite in float (1e-300 gave infinite albedo and NaN normals).
constexpr double kMinLightIntensity = 1e-30, kMaxLightIntensity = 1e30;
inline bool LightIntensityInRange(const Vec3d& e) {
  return (e.array() >= kMinLightIntensity).all() && (e.array() <= kMaxLightIntensity).all();
}

struct PhotometricData {
  int width = 0;
  int height = 0;
  int images = 0;                        // K
  std::vector<int> pixels;               // row-major index of each masked pixel
  std::vector<float> values;             // pixels × K × 3, linear
  std::vector<Vec3d> light_directions;   // K, unit
  std::vector<Vec3d> light_intensities;  // K, RGB, > 0
  // Near lights: K point lights (empty: distant lights), each pixel's surface point (same units
  // as the lights' positions, camera frame) and whether V is per point (perspective).
  std::vector<reflectance::Light> point_lights;
  std::vector<Vec3d> points_cam;  // per masked pixel, with point_lights
  bool perspective = false;

  std::size_t pixel_count() const { return pixels.size(); }
  bool near() const { return !point_lights.empty(); }
  const float* pixel(std::size_t p) const { return values.data() + p * images * 3; }
  std::string Validate() const;
};

// What pixel p of `data` sees: each light's unit direction L_j and RGB irradiance E_j, and the
// view direction V. Distant lights: the shared directions and intensities, V = (0, 0, 1). Near
// lights: reflectance::LightAt from the pixel's surface point; a light the point sees with no
// irradiance in some channel (behind an LED, or at the light itself) is not lit().
class PixelLights {
 public:
  // Points at the shared arrays of `data` until At() is called on near data.
  explicit PixelLights(const PhotometricData& data);
  void At(std::size_t p);
  const Vec3d& direction(int j) const { return directions_[j]; }
  const Vec3d& irradiance(int j) const { return irradiance_[j]; }
  const Vec3d& view() const { return view_; }
  bool lit(int j) const { return (irradiance_[j].array() > 0).all(); }
  const std::vector<Vec3d>& directions() const { return *directions_ptr_; }

 private:
  const PhotometricData& data_;
  std::vector<Vec3d> near_directions_, near_irradiance_;
  const Vec3d* directions_ = nullptr;
  const Vec3d* irradiance_ = nullptr;
  const std::vector<Vec3d>* directions_ptr_ = nullptr;
  Vec3d view_ = Vec3d(0, 0, 1);
};

// The shared light_directions and light_intensities of near data: its point lights as seen from
// `reference_cam` (its surface's centre, say); a light with no direction there (the point at the
// light) gets (0, 0, 1), one that sends it nothing its own intensity.
void SetReferenceLights(PhotometricData& data, const Vec3d& reference_cam);

// "" when three or more light directions span all three dimensions, else what is wrong: with all
// lights in one plane through the surface (or all the same) the normal's component across that
// plane is not determined by any pixel's shading. One or two lights are left to the global solver.
std::string CheckLightSpan(const std::vector<Vec3d>& light_directions);

// Lights behind the surface's plane as the camera sees it (z < 0). A few are a rim setup; more
// than half is a file in another frame (y down and z into the scene), whose fix (y and z negated)
// is not another reading of the image plane or of the depth axis: the frame checks leave it to
// the light file's own warning.
std::size_t LightsBehind(const std::vector<Vec3d>& light_directions);
inline bool MostLightsBehind(const std::vector<Vec3d>& light_directions) {
  return 2 * LightsBehind(light_directions) > light_directions.size();
}

// The step of the integer codes the values are, 1/(2^b − 1) for the fewest bits b in 8…16 that
// put every value within 1 % of a step of a code (an 8-bit file read as linear: 1/255), or 0
// when they are not codes (floating-point files, downscaled or sRGB-decoded ones).
double IntegerCodeStep(const PhotometricData& data);

// A recorded value taken at the middle of its integer code's interval: `offset` (half a code
// step) added when the images were truncated to codes, zero kept as zero (shadow, not a value).
inline double AtCodeMiddle(double value, double offset) {
  return value > 0 ? value + offset : value;
}

// The level at or above which a pixel's recorded values count as clipped, given the brightest
// of them. A level of at most 1 is the top of data scaled to [0, 1] — integer codes, and float
// files made from them — and applies while the values stay within 1; values above 1 were not
// clipped at 1 (a floating-point, high-dynamic-range capture), so none is (infinity). A level
// above 1 is a caller's own and always applies. The one rule of the solver, the material fitter
// and the light calibration.
inline double SaturationLevel(double level, double brightest) {
  return level <= 1 && brightest > 1 ? std::numeric_limits<double>::infinity() : level;
}

// SaturationLevel for one pixel's `count` recorded values. Decided per pixel so a pixel's result
// depends on its own observations alone, whichever piece of the image it is in.
inline double PixelSaturation(const float* values, std::size_t count, double level) {
  float brightest = 0;
  for (std::size_t i = 0; i < count; ++i) brightest = std::max(brightest, values[i]);
  return SaturationLevel(level, brightest);
}

// The observations' layout for K images: the masked pixels and the lights, values zeroed.
// Throws std::invalid_argument when the mask is not width×height.
PhotometricData ObservationLayout(int width, int height, const Mask& mask,
                                  const std::vector<Vec3d>& light_directions,
                                  const std::vector<Vec3d>& light_intensities);

// Copies the masked pixels of image j (width×height×3, row-major from the top) into `data`.
// Returns "" or what is wrong with the image. Images may be gathered concurrently.
std::string GatherImage(PhotometricData& data, int j, const float* rgb);

// The mean of the surface points of near data (the origin for distant data).
Vec3d MeanPoint(const PhotometricData& data);

// Gathers the masked pixels of K images (each width×height×3, row-major from the top).
// Throws std::invalid_argument when sizes, counts or lights are inconsistent or not finite.
PhotometricData GatherObservations(const std::vector<const float*>& images, int width, int height,
                                   const Mask& mask, const std::vector<Vec3d>& light_directions,
                                   const std::vector<Vec3d>& light_intensities);

}  // namespace iphong::solve
