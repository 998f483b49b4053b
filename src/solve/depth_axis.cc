#include "solve/depth_axis.h"

#include <algorithm>
#include <cstdio>
#include <utility>
#include <vector>

#include "solve/woodham.h"

namespace iphong::solve {

void DepthAxisCounts::Add(const PhotometricData& data, std::size_t stride) {
  if (data.near() || data.images < 3 || data.pixel_count() == 0) return;
  const Eigen::Matrix3Xd pinv = WoodhamPseudoInverse(data);
  const WoodhamSettings settings;
  std::vector<std::pair<double, int>> order;
  order.reserve(data.images);
  PixelLights lights(data);
  for (std::size_t p = 0; p < data.pixel_count(); p += std::max<std::size_t>(1, stride)) {
    const internal::PixelSolution s = Woodham(data, p, settings, pinv, order, lights, false);
    if (s.status != internal::PixelStatus::kSolved || !s.normal.allFinite()) continue;
    ++pixels_;
    for (int a = 0; a < 3; ++a) {
      away_[a][0] += s.normal[a] < 0;
      away_[a][1] += s.normal[a] > 0;
    }
  }
}

DepthAxisCheck DepthAxisCounts::Result() const {
  DepthAxisCheck c;
  c.pixels = pixels_;
  if (pixels_ == 0) return c;
  const double n = static_cast<double>(pixels_);
  c.facing_away = away_[2][0] / n;
  c.best_facing = c.facing_away;
  for (int a = 0; a < 2; ++a) {
    for (int s = 0; s < 2; ++s) {
      if (away_[a][s] / n < c.best_facing) {
        c.best_facing = away_[a][s] / n;
        c.best_axis = a;
        c.best_sign = s == 0 ? 1 : -1;
      }
    }
  }
  if (c.facing_away >= kDepthAxisShare && c.best_axis != 2 &&
      c.best_facing <= 0.2 * c.facing_away) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "Woodham's normals face away from the camera at %.0f%% of %zu pixels; with the "
                  "lights' %s as the depth axis (toward the camera) at %.1f%%",
                  100 * c.facing_away, c.pixels, c.BestAxisName().c_str(), 100 * c.best_facing);
    c.message = text;
  }
  return c;
}

DepthAxisCheck CheckDepthAxis(const PhotometricData& data, std::size_t sample) {
  DepthAxisCounts counts;
  const std::size_t n = data.pixel_count();
  counts.Add(data, sample > 0 && n > sample ? (n + sample - 1) / sample : 1);
  return counts.Result();
}

}  // namespace iphong::solve
