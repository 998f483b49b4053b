// Lights shared by the benchmarks: k directions on a golden-angle spiral over the cap of the
// hemisphere from the view axis down to elevation asin(0.4) ≈ 24°.
#pragma once

#include <cmath>
#include <vector>

#include "core/types.h"

namespace iphong::bench {

inline std::vector<Vec3d> SpiralLights(int k) {
  std::vector<Vec3d> lights;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int j = 0; j < k; ++j) {
    const double z = 1 - 0.6 * (j + 0.5) / k, r = std::sqrt(1 - z * z);
    lights.emplace_back(r * std::cos(golden * j), r * std::sin(golden * j), z);
  }
  return lights;
}

}  // namespace iphong::bench
