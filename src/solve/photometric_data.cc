#include "solve/photometric_data.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace iphong::solve {

std::size_t LightsBehind(const std::vector<Vec3d>& light_directions) {
  std::size_t behind = 0;
  for (const Vec3d& l : light_directions) behind += l.z() < 0;
  return behind;
}

std::string CheckLightSpan(const std::vector<Vec3d>& light_directions) {
  if (light_directions.size() < 3) return "";
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Vec3d& l : light_directions) scatter += l * l.transpose();
  const Eigen::Vector3d spread =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvalues();  // ascending
  // The smallest over the largest: 1e-6 is a spread of 0.1% of a radian out of the plane.
  if (!(spread[0] > 1e-6 * spread[2])) {
    return "the " + std::to_string(light_directions.size()) +
           " light directions lie in one plane (or are all the same): the normal is not "
           "determined; photometric stereo needs three lights that are not coplanar";
  }
  return "";
}

std::string PhotometricData::Validate() const {
  if (images < 1) return "photometric stereo needs at least one image";
  if (light_directions.size() != static_cast<std::size_t>(images) ||
      light_intensities.size() != static_cast<std::size_t>(images)) {
    return std::to_string(images) + " images but " + std::to_string(light_directions.size()) +
           " light directions and " + std::to_string(light_intensities.size()) + " intensities";
  }
  for (int j = 0; j < images; ++j) {
    if (!light_directions[j].allFinite() || std::abs(light_directions[j].norm() - 1) > 1e-6) {
      return "light direction " + std::to_string(j + 1) + " is not a finite unit vector";
    }
    if (!LightIntensityInRange(light_intensities[j])) {
      return "light intensity " + std::to_string(j + 1) + " must be between 1e-30 and 1e30";
    }
  }
  if (values.size() != pixels.size() * images * 3) return "observation array has the wrong size";
  if (near()) {
    if (point_lights.size() != static_cast<std::size_t>(images)) {
      return std::to_string(images) + " images but " + std::to_string(point_lights.size()) +
             " point lights";
    }
    for (int j = 0; j < images; ++j) {
      if (point_lights[j].type != reflectance::LightType::kPoint) {
        return "light " + std::to_string(j + 1) + " of a near-light capture is not a point light";
      }
      if (auto m = point_lights[j].Validate(); !m.empty()) {
        return "light " + std::to_string(j + 1) + ": " + m;
      }
    }
    if (points_cam.size() != pixels.size()) {
      return std::to_string(pixels.size()) + " pixels but " + std::to_string(points_cam.size()) +
             " surface points";
    }
    for (const Vec3d& x : points_cam) {
      if (!x.allFinite()) return "a surface point is not finite";
    }
  }
  return CheckLightSpan(light_directions);
}

PixelLights::PixelLights(const PhotometricData& data)
    : data_(data),
      directions_(data.light_directions.data()),
      irradiance_(data.light_intensities.data()),
      directions_ptr_(&data.light_directions) {
  if (data.near()) {
    near_directions_.resize(data.images);
    near_irradiance_.resize(data.images);
  }
}

void PixelLights::At(std::size_t p) {
  if (!data_.near()) return;
  const Vec3d& x = data_.points_cam[p];
  for (int j = 0; j < data_.images; ++j) {
    Vec3d specular;
    if (!reflectance::LightAt<double>(data_.point_lights[j], x, &near_directions_[j],
                                      &near_irradiance_[j], &specular)) {
      near_directions_[j] = Vec3d(0, 0, 1);
      near_irradiance_[j].setZero();
    }
  }
  directions_ = near_directions_.data();
  irradiance_ = near_irradiance_.data();
  directions_ptr_ = &near_directions_;
  const double distance = x.norm();
  view_ = data_.perspective && distance > 0 ? Vec3d(-x / distance) : Vec3d(0, 0, 1);
}

void SetReferenceLights(PhotometricData& data, const Vec3d& reference_cam) {
  data.light_directions.resize(data.point_lights.size());
  data.light_intensities.resize(data.point_lights.size());
  for (std::size_t j = 0; j < data.point_lights.size(); ++j) {
    const reflectance::Light& light = data.point_lights[j];
    Vec3d direction, irradiance, specular;
    if (!reflectance::LightAt<double>(light, reference_cam, &direction, &irradiance, &specular)) {
      direction = Vec3d(0, 0, 1);  // the point at the light: no direction to start from
    }
    data.light_directions[j] = direction;
    // Only a start for the tables: a light that sends the point nothing (behind an LED) keeps
    // its own intensity there, so the shared intensities stay valid.
    data.light_intensities[j] = (irradiance.array() > 0).all()
                                    ? irradiance
                                    : Vec3d(light.diffuse_intensity.cwiseMax(kMinLightIntensity));
  }
}

Vec3d MeanPoint(const PhotometricData& data) {
  if (data.points_cam.empty()) return Vec3d::Zero();
  Vec3d sum = Vec3d::Zero();
  for (const Vec3d& x : data.points_cam) sum += x;
  return sum / static_cast<double>(data.points_cam.size());
}

double IntegerCodeStep(const PhotometricData& data) {
  if (data.values.empty()) return 0;
  for (int bits = 8; bits <= 16; ++bits) {
    const double codes = std::ldexp(1.0, bits) - 1;
    // Most data fail on their first values; codes of a deeper file also pass at more bits.
    const bool all = std::all_of(data.values.begin(), data.values.end(), [&](float v) {
      const double k = v * codes;
      return std::abs(k - std::round(k)) < 1e-2;  // floats hold 16-bit codes to ~4e-3
    });
    if (all) return 1 / codes;
  }
  return 0;
}

PhotometricData ObservationLayout(int width, int height, const Mask& mask,
                                  const std::vector<Vec3d>& light_directions,
                                  const std::vector<Vec3d>& light_intensities) {
  if (mask.width != width || mask.height != height) {
    throw std::invalid_argument("the mask is " + SizeText(mask.width, mask.height) +
                                ", the images " + SizeText(width, height));
  }
  PhotometricData data;
  data.width = width;
  data.height = height;
  data.images = static_cast<int>(light_directions.size());
  data.light_directions = light_directions;
  data.light_intensities = light_intensities;
  for (int p = 0; p < width * height; ++p)
    if (mask.inside[p]) data.pixels.push_back(p);
  data.values.assign(data.pixels.size() * data.images * 3, 0.0f);
  return data;
}

std::string GatherImage(PhotometricData& data, int j, const float* rgb) {
  const std::size_t k = data.images;
  for (std::size_t i = 0; i < data.pixels.size(); ++i) {
    const float* src = rgb + 3 * static_cast<std::size_t>(data.pixels[i]);
    float* dst = data.values.data() + (i * k + j) * 3;
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(src[c])) return "has a non-finite value";
      dst[c] = src[c];
    }
  }
  return "";
}

PhotometricData GatherObservations(const std::vector<const float*>& images, int width, int height,
                                   const Mask& mask, const std::vector<Vec3d>& light_directions,
                                   const std::vector<Vec3d>& light_intensities) {
  if (images.size() != light_directions.size()) {
    throw std::invalid_argument(std::to_string(images.size()) + " images but " +
                                std::to_string(light_directions.size()) + " light directions");
  }
  PhotometricData data =
      ObservationLayout(width, height, mask, light_directions, light_intensities);
  for (std::size_t j = 0; j < images.size(); ++j) {
    if (auto m = GatherImage(data, static_cast<int>(j), images[j]); !m.empty()) {
      throw std::invalid_argument("image " + std::to_string(j + 1) + " " + m);
    }
  }
  if (auto m = data.Validate(); !m.empty()) throw std::invalid_argument(m);
  return data;
}

}  // namespace iphong::solve
