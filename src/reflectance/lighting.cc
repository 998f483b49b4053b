#include "reflectance/lighting.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace iphong::reflectance {
namespace {

std::string Format(const Vec3d& v) {
  std::ostringstream out;
  out << "[" << v[0] << ", " << v[1] << ", " << v[2] << "]";
  return out.str();
}

std::string CheckIntensity(const char* what, const Rgb& intensity) {
  // Images are float: 1e308 rendered infinity everywhere behind success.
  if (!intensity.allFinite() || (intensity.array() < 0).any() || (intensity.array() > 1e30).any()) {
    return std::string("light ") + what + " must be between 0 and 1e30, got " + Format(intensity);
  }
  return "";
}

void ThrowIf(const std::string& message) {
  if (!message.empty()) throw std::invalid_argument(message);
}

}  // namespace

Light Light::Directional(const Vec3d& direction_cam, const Rgb& intensity) {
  return Directional(direction_cam, intensity, intensity);
}

Light Light::Directional(const Vec3d& direction_cam, const Rgb& diffuse_intensity,
                         const Rgb& specular_intensity) {
  Light light;
  light.type = LightType::kDirectional;
  light.diffuse_intensity = diffuse_intensity;
  light.specular_intensity = specular_intensity;
  // Scaled by the largest component first: 1e308 components have a direction, not an infinite
  // norm (which divided them to zero).
  const double scale = direction_cam.cwiseAbs().maxCoeff();
  if (!direction_cam.allFinite() || !(scale > 0)) {
    throw std::invalid_argument("light direction must be finite and non-zero, got " +
                                Format(direction_cam));
  }
  light.direction_cam = (direction_cam / scale).normalized();
  ThrowIf(light.Validate());
  return light;
}

Light Light::Point(const Vec3d& position_cam, const Rgb& intensity, bool inverse_square_falloff) {
  return Point(position_cam, intensity, intensity, inverse_square_falloff);
}

Light Light::Point(const Vec3d& position_cam, const Rgb& diffuse_intensity,
                   const Rgb& specular_intensity, bool inverse_square_falloff) {
  Light light;
  light.type = LightType::kPoint;
  light.position_cam = position_cam;
  light.diffuse_intensity = diffuse_intensity;
  light.specular_intensity = specular_intensity;
  light.inverse_square_falloff = inverse_square_falloff;
  ThrowIf(light.Validate());
  return light;
}

Light Light::Led(const Vec3d& position_cam, const Rgb& intensity, const Vec3d& axis_cam,
                 double anisotropy) {
  Light light = Point(position_cam, intensity, true);
  const double scale = axis_cam.cwiseAbs().maxCoeff();
  if (!axis_cam.allFinite() || !(scale > 0)) {
    throw std::invalid_argument("light axis must be finite and non-zero, got " + Format(axis_cam));
  }
  light.axis_cam = (axis_cam / scale).normalized();
  light.anisotropy = anisotropy;
  ThrowIf(light.Validate());
  return light;
}

std::string Light::Validate() const {
  if (type == LightType::kDirectional) {
    if (!direction_cam.allFinite() || std::abs(direction_cam.norm() - 1.0) > 1e-6) {
      return "light direction must be a finite unit vector, got " + Format(direction_cam);
    }
  } else if (!position_cam.allFinite()) {
    return "light position must be finite, got " + Format(position_cam);
  } else if (!std::isfinite(anisotropy) || anisotropy < 0 || anisotropy > 1000) {
    return "light anisotropy must be in 0..1000, got " + std::to_string(anisotropy);
  } else if (anisotropy > 0 && (!axis_cam.allFinite() || std::abs(axis_cam.norm() - 1.0) > 1e-6)) {
    return "light axis must be a finite unit vector, got " + Format(axis_cam);
  }
  if (auto m = CheckIntensity("diffuse intensity", diffuse_intensity); !m.empty()) return m;
  return CheckIntensity("specular intensity", specular_intensity);
}

std::string Lighting::Validate() const {
  if (!ambient.allFinite() || (ambient.array() < 0).any()) {
    return "ambient intensity must be finite and >= 0, got " + Format(ambient);
  }
  for (std::size_t i = 0; i < lights.size(); ++i) {
    if (auto m = lights[i].Validate(); !m.empty()) return "light " + std::to_string(i) + ": " + m;
  }
  return "";
}

bool Lighting::HasPointLights() const {
  for (const Light& light : lights) {
    if (light.type == LightType::kPoint) return true;
  }
  return false;
}

}  // namespace iphong::reflectance
