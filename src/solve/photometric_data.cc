#include "solve/photometric_data.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace iphong::solve {

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
    if (!light_intensities[j].allFinite() || !(light_intensities[j].array() > 0).all()) {
      return "light intensity " + std::to_string(j + 1) + " must be finite and > 0";
    }
  }
  if (values.size() != pixels.size() * images * 3) return "observation array has the wrong size";
  return CheckLightSpan(light_directions);
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
