#include "solve/light_tiles.h"

#include <cmath>
#include <numeric>

#include "solve/model_choice.h"

namespace iphong::solve {
namespace {

// Light j's direction from `point`; (0, 0, 1) where it has none (the point at the light).
Vec3d DirectionFrom(const reflectance::Light& light, const Vec3d& point) {
  Vec3d direction, diffuse, specular;
  if (!reflectance::LightAt<double>(light, point, &direction, &diffuse, &specular)) {
    return Vec3d(0, 0, 1);
  }
  return direction;
}

struct Square {
  int col0, row0, col1, row1;  // [col0, col1) × [row0, row1)
  std::vector<std::size_t> pixels;
};

}  // namespace

double TileToleranceDeg(reflectance::Lobe lobe, double shininess) {
  if (lobe == reflectance::Lobe::kLambert || lobe == reflectance::Lobe::kOrenNayar) return 8;
  return std::clamp(0.5 * LobeHalfWidthDeg(lobe, shininess), 1.0, 8.0);
}

std::vector<LightTile> MakeLightTiles(const PhotometricData& data, double tolerance_deg,
                                      const std::vector<std::size_t>* pixels) {
  std::vector<std::size_t> all;
  if (!pixels) {
    all.resize(data.pixel_count());
    std::iota(all.begin(), all.end(), std::size_t{0});
  }
  const std::vector<std::size_t>& chosen = pixels ? *pixels : all;
  std::vector<LightTile> tiles;
  if (chosen.empty()) return tiles;
  if (!data.near()) {
    tiles.push_back({chosen, data.light_directions});
    return tiles;
  }
  const double min_cos = std::cos(tolerance_deg * M_PI / 180);
  const int k = data.images;
  Square whole{data.width, data.height, 0, 0, chosen};
  for (std::size_t i : chosen) {
    const int p = data.pixels[i];
    const int col = p % data.width, row = p / data.width;
    whole.col0 = std::min(whole.col0, col);
    whole.row0 = std::min(whole.row0, row);
    whole.col1 = std::max(whole.col1, col + 1);
    whole.row1 = std::max(whole.row1, row + 1);
  }
  std::vector<Square> stack;
  stack.push_back(std::move(whole));
  std::vector<Vec3d> reference(k);
  while (!stack.empty()) {
    Square square = std::move(stack.back());
    stack.pop_back();
    Vec3d mean = Vec3d::Zero();
    for (std::size_t i : square.pixels) mean += data.points_cam[i];
    mean /= static_cast<double>(square.pixels.size());
    for (int j = 0; j < k; ++j) reference[j] = DirectionFrom(data.point_lights[j], mean);
    bool close = true;
    for (std::size_t n = 0; n < square.pixels.size() && close; ++n) {
      const Vec3d& x = data.points_cam[square.pixels[n]];
      for (int j = 0; j < k && close; ++j) {
        close = DirectionFrom(data.point_lights[j], x).dot(reference[j]) >= min_cos;
      }
    }
    const int w = square.col1 - square.col0, h = square.row1 - square.row0;
    if (close || (w <= 1 && h <= 1)) {
      tiles.push_back({std::move(square.pixels), reference});
      continue;
    }
    const int mc = square.col0 + (w + 1) / 2, mr = square.row0 + (h + 1) / 2;
    Square parts[4] = {{square.col0, square.row0, mc, mr, {}},
                       {mc, square.row0, square.col1, mr, {}},
                       {square.col0, mr, mc, square.row1, {}},
                       {mc, mr, square.col1, square.row1, {}}};
    for (std::size_t i : square.pixels) {
      const int p = data.pixels[i];
      const int col = p % data.width, row = p / data.width;
      parts[(col >= mc ? 1 : 0) + (row >= mr ? 2 : 0)].pixels.push_back(i);
    }
    for (Square& part : parts) {
      if (!part.pixels.empty()) stack.push_back(std::move(part));
    }
  }
  return tiles;
}

}  // namespace iphong::solve
