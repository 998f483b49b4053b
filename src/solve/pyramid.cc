#include "solve/pyramid.h"

#include <algorithm>
#include <cmath>

namespace iphong::solve {

PhotometricData HalveObservations(const PhotometricData& fine) {
  PhotometricData coarse;
  coarse.width = (fine.width + 1) / 2;
  coarse.height = (fine.height + 1) / 2;
  coarse.images = fine.images;
  coarse.light_directions = fine.light_directions;
  coarse.light_intensities = fine.light_intensities;
  const std::size_t cells = static_cast<std::size_t>(coarse.width) * coarse.height;
  std::vector<unsigned char> inside(cells, 0);
  for (int p : fine.pixels) ++inside[(p / fine.width / 2) * coarse.width + (p % fine.width) / 2];
  std::vector<int> index(cells, -1);
  for (int r = 0; r < coarse.height; ++r) {
    for (int c = 0; c < coarse.width; ++c) {
      // Children in the image: 4, fewer on the last column or row of an odd size.
      const int children =
          (std::min(2 * c + 2, fine.width) - 2 * c) * (std::min(2 * r + 2, fine.height) - 2 * r);
      const std::size_t cell = static_cast<std::size_t>(r) * coarse.width + c;
      if (2 * inside[cell] >= children) {
        index[cell] = static_cast<int>(coarse.pixels.size());
        coarse.pixels.push_back(static_cast<int>(cell));
      }
    }
  }
  const std::size_t values = static_cast<std::size_t>(fine.images) * 3;
  std::vector<double> sum(coarse.pixels.size() * values, 0.0);
  std::vector<int> count(coarse.pixels.size(), 0);
  for (std::size_t i = 0; i < fine.pixel_count(); ++i) {
    const int p = fine.pixels[i];
    const int at = index[(p / fine.width / 2) * coarse.width + (p % fine.width) / 2];
    if (at < 0) continue;
    const float* v = fine.pixel(i);
    double* s = sum.data() + static_cast<std::size_t>(at) * values;
    for (std::size_t k = 0; k < values; ++k) s[k] += v[k];
    ++count[at];
  }
  coarse.values.resize(sum.size());
  for (std::size_t i = 0; i < coarse.pixels.size(); ++i) {
    for (std::size_t k = 0; k < values; ++k) {
      coarse.values[i * values + k] = static_cast<float>(sum[i * values + k] / count[i]);
    }
  }
  return coarse;
}

std::vector<PhotometricData> ObservationPyramid(const PhotometricData& fine,
                                                std::size_t coarsest_pixels, int max_levels) {
  std::vector<PhotometricData> levels{fine};
  while (static_cast<int>(levels.size()) < max_levels &&
         levels.back().pixel_count() > coarsest_pixels && levels.back().width > 1 &&
         levels.back().height > 1) {
    PhotometricData next = HalveObservations(levels.back());
    if (next.pixel_count() == 0) break;
    levels.push_back(std::move(next));
  }
  return levels;
}

std::vector<Vec3d> UpsampleNormals(const PhotometricData& coarse,
                                   const std::vector<Vec3d>& coarse_normals,
                                   const PhotometricData& fine) {
  std::vector<int> index(static_cast<std::size_t>(coarse.width) * coarse.height, -1);
  for (std::size_t i = 0; i < coarse.pixel_count(); ++i)
    index[coarse.pixels[i]] = static_cast<int>(i);
  const auto at = [&](int c, int r) {
    return c < 0 || r < 0 || c >= coarse.width || r >= coarse.height
               ? -1
               : index[static_cast<std::size_t>(r) * coarse.width + c];
  };
  std::vector<Vec3d> out(fine.pixel_count(), Vec3d(0, 0, 1));
  for (std::size_t i = 0; i < fine.pixel_count(); ++i) {
    const int col = fine.pixels[i] % fine.width, row = fine.pixels[i] / fine.width;
    // The fine pixel centre in coarse pixel coordinates (centres at integers).
    const double u = (col + 0.5) / 2 - 0.5, v = (row + 0.5) / 2 - 0.5;
    const int c0 = static_cast<int>(std::floor(u)), r0 = static_cast<int>(std::floor(v));
    const double fu = u - c0, fv = v - r0;
    Vec3d sum = Vec3d::Zero();
    for (int dr = 0; dr < 2; ++dr) {
      for (int dc = 0; dc < 2; ++dc) {
        const int j = at(c0 + dc, r0 + dr);
        if (j >= 0) sum += (dc ? fu : 1 - fu) * (dr ? fv : 1 - fv) * coarse_normals[j];
      }
    }
    if (sum.norm() > 1e-9) {
      out[i] = sum.normalized();
      continue;
    }
    // Outside the coarse mask's reach (its outline moved by the halving): the nearest one.
    double best = INFINITY;
    for (int dr = -2; dr <= 2; ++dr) {
      for (int dc = -2; dc <= 2; ++dc) {
        const int j = at(col / 2 + dc, row / 2 + dr);
        if (j >= 0 && dc * dc + dr * dr < best)
          best = dc * dc + dr * dr, out[i] = coarse_normals[j];
      }
    }
  }
  return out;
}

}  // namespace iphong::solve
