// Lights in the camera frame, and the full model summed over them.
//
// A directional light has one unit direction L (surface → light) for every point. A point light
// has a position S; at surface point X its direction is L = (S − X)/|S − X| and, with falloff, its
// intensities are divided by |S − X|². A point light may be an LED with an axis a and anisotropy
// μ (LUCES' and Quéau et al.'s model, SPEC.md "Near lights"): its intensities toward X are scaled
// by (a·(X − S)/|X − S|)^μ, zero behind it; μ = 0 is an isotropic point light. So the irradiance
// a point sees is E(X) = Φ·(a·(X − S)/|X − S|)^μ / |X − S|², Φ the light's intensity.
// Ambient light is one RGB triple for the scene.
#pragma once

#include <string>
#include <vector>

#include "core/types.h"
#include "reflectance/phong.h"

namespace iphong::reflectance {

enum class LightType { kDirectional, kPoint };

struct Light {
  LightType type = LightType::kDirectional;
  Vec3d direction_cam = Vec3d(0, 0, 1);  // unit, surface → light (directional lights)
  Vec3d position_cam = Vec3d::Zero();    // scene units (point lights)
  Rgb diffuse_intensity = Rgb::Ones();   // seed 003's i_d
  Rgb specular_intensity = Rgb::Ones();  // seed 003's i_s
  bool inverse_square_falloff = true;    // point lights only
  // Point lights: the LED's axis (unit, the way it points) and anisotropy μ ≥ 0 (0: isotropic,
  // the axis unused; 1: a Lambertian emitter).
  Vec3d axis_cam = Vec3d(0, 0, -1);
  double anisotropy = 0;

  // Throws std::invalid_argument naming the problem (zero or non-finite direction, negative
  // or non-finite intensity). The direction is normalized.
  static Light Directional(const Vec3d& direction_cam, const Rgb& intensity);
  static Light Directional(const Vec3d& direction_cam, const Rgb& diffuse_intensity,
                           const Rgb& specular_intensity);
  static Light Point(const Vec3d& position_cam, const Rgb& intensity, bool inverse_square_falloff);
  static Light Point(const Vec3d& position_cam, const Rgb& diffuse_intensity,
                     const Rgb& specular_intensity, bool inverse_square_falloff);
  // A point light with the inverse-square falloff whose intensity follows an LED's axis with
  // anisotropy μ (the axis is normalized; μ = 0 makes it isotropic).
  static Light Led(const Vec3d& position_cam, const Rgb& intensity, const Vec3d& axis_cam,
                   double anisotropy);

  // Empty when valid, else a one-line message.
  std::string Validate() const;
};

struct Lighting {
  Rgb ambient = Rgb::Zero();  // Ia
  std::vector<Light> lights;

  std::string Validate() const;
  bool HasPointLights() const;
};

// The factor a point light's intensities are scaled by at a point whose unit direction toward the
// light is `light_dir_cam`: (a·(X − S)/|X − S|)^μ = (−a·L)^μ, 0 behind an LED, 1 for μ = 0.
template <typename T>
T LedFactor(const Light& light, const Vec3T<T>& light_dir_cam) {
  using std::exp;
  using std::log;
  if (!(light.anisotropy > 0)) return T(1);
  const T cosine = -light_dir_cam.dot(light.axis_cam.template cast<T>());
  if (!(cosine > T(0))) return T(0);
  if (light.anisotropy == 1) return cosine;
  return exp(T(light.anisotropy) * log(cosine));
}

// Light `light` as seen from a surface point: the unit direction toward it and its intensities
// there (for a point light: the LED factor, and divided by d² with falloff). False where no
// direction is defined (the point sits on a point light).
template <typename T>
bool LightAt(const Light& light, const Vec3T<T>& position_cam, Vec3T<T>* light_dir_cam,
             Vec3T<T>* diffuse, Vec3T<T>* specular) {
  using std::sqrt;
  *diffuse = light.diffuse_intensity.template cast<T>();
  *specular = light.specular_intensity.template cast<T>();
  if (light.type == LightType::kDirectional) {
    *light_dir_cam = light.direction_cam.template cast<T>();
    return true;
  }
  const Vec3T<T> to_light = light.position_cam.template cast<T>() - position_cam;
  const T distance2 = to_light.squaredNorm();
  if (!(distance2 > T(0))) return false;
  *light_dir_cam = to_light / sqrt(distance2);
  T scale = LedFactor(light, *light_dir_cam);
  if (light.inverse_square_falloff) scale /= distance2;
  *diffuse *= scale;
  *specular *= scale;
  return true;
}

// The full model at one surface point: ambient plus every light j for which
// visible(j, light_dir_cam) holds (the renderer's cast shadows and single-light images).
// `position_cam` is only read for point lights. Vectors are unit, camera frame.
template <typename T, typename Visible>
Vec3T<T> ShadeVisible(const Vec3T<T>& normal_cam, const Vec3T<T>& view_cam,
                      const Vec3T<T>& position_cam, const MaterialT<T>& material,
                      const Lighting& lighting, const ModelOptions& options, Visible visible) {
  Vec3T<T> color = AmbientTerm(Vec3T<T>(lighting.ambient.template cast<T>()), material);
  for (std::size_t j = 0; j < lighting.lights.size(); ++j) {
    Vec3T<T> light_dir_cam, diffuse, specular;
    if (!LightAt(lighting.lights[j], position_cam, &light_dir_cam, &diffuse, &specular)) continue;
    if (!visible(j, light_dir_cam)) continue;
    color += LightTerm(normal_cam, view_cam, light_dir_cam, diffuse, specular, material, options);
  }
  return color;
}

// The full model at one surface point: ambient plus every light.
template <typename T>
Vec3T<T> Shade(const Vec3T<T>& normal_cam, const Vec3T<T>& view_cam, const Vec3T<T>& position_cam,
               const MaterialT<T>& material, const Lighting& lighting,
               const ModelOptions& options) {
  return ShadeVisible(normal_cam, view_cam, position_cam, material, lighting, options,
                      [](std::size_t, const Vec3T<T>&) { return true; });
}

}  // namespace iphong::reflectance
