// The effective distance (near/effective_distance.h) on a capture read in bands of rows against
// the same on the whole capture: the same D, and every pixel's result bit for bit.
#include <gtest/gtest.h>

#include <cmath>

#include "near/effective_distance.h"
#include "near/near_scenes.h"

namespace iphong::near {
namespace {

using test_data::Dome;
using test_data::NearScene;
using test_data::RenderNearSphere;

// The observations of rows [y0, y1), pixel indices within the band.
solve::PhotometricData Rows(const solve::PhotometricData& data, int y0, int y1) {
  solve::PhotometricData band;
  band.width = data.width;
  band.height = y1 - y0;
  band.images = data.images;
  band.light_directions = data.light_directions;
  band.light_intensities = data.light_intensities;
  const std::size_t k3 = static_cast<std::size_t>(data.images) * 3;
  for (std::size_t i = 0; i < data.pixel_count(); ++i) {
    const int p = data.pixels[i];
    if (p < y0 * data.width || p >= y1 * data.width) continue;
    band.pixels.push_back(p - y0 * data.width);
    band.values.insert(band.values.end(), data.pixel(i), data.pixel(i) + k3);
  }
  return band;
}

void ExpectSame(const ImageF& banded, const ImageF& whole, const char* what) {
  ASSERT_EQ(banded.pixels.size(), whole.pixels.size()) << what;
  for (std::size_t i = 0; i < whole.pixels.size(); ++i) {
    if (std::isnan(whole.pixels[i]) && std::isnan(banded.pixels[i])) continue;  // outside
    ASSERT_EQ(banded.pixels[i], whole.pixels[i]) << what << " value " << i;
  }
}

// A glossy sphere under a dome of 24 lights at 3 object sizes, seen orthographically and read
// with directions only (the case the effective distance is for): D is chosen, the surface's points
// explain its gain, passes run, and bands change nothing.
TEST(EffectiveDistance, InBandsEqualsTheWholeBitForBit) {
  NearScene s;
  s.width = 44;
  s.height = 40;
  s.frame.perspective = false;
  s.frame.pixel_size = 2.8;  // mm: the sphere is 36 pixels wide
  s.lights = Dome(s.center, 6 * s.radius, 24, 2e4 * 4);
  s.material.kd = Vec3d(0.7, 0.6, 0.5);
  solve::PhotometricData data = RenderNearSphere(s).data;
  data.point_lights.clear();  // directions only
  data.perspective = false;

  EffectiveDistanceOptions options;
  options.normals.plan_sample = 600;   // below the pixel count: a stride sample
  options.normals.model_sample = 200;  // the choice's cost, which dominates here
  const EffectiveDistanceResult whole = SolveEffectiveDistance(data, options);
  ASSERT_TRUE(std::isfinite(whole.distance_px));
  ASSERT_FALSE(whole.passes.empty());
  // The lights are near: at the D chosen the surface's points predict held-out lights better than
  // points placed by their normals (near::PositionCheck), by both fits.
  ASSERT_FALSE(whole.position_checks.empty());
  for (const PositionCheck& check : whole.position_checks) EXPECT_FALSE(check.refused);

  for (int band_rows : {5, 40}) {
    SCOPED_TRACE(band_rows);
    solve::BandSource source;
    source.width = data.width;
    source.height = data.height;
    source.masked_pixels = data.pixel_count();
    source.read = [&](int y0, int y1, bool) { return Rows(data, y0, y1); };
    const EffectiveDistanceResult banded =
        SolveEffectiveDistanceInBands(source, band_rows, options);
    EXPECT_EQ(banded.distance_px, whole.distance_px);
    ASSERT_EQ(banded.position_checks.size(), whole.position_checks.size());
    for (std::size_t i = 0; i < whole.position_checks.size(); ++i) {
      EXPECT_EQ(banded.position_checks[i].gain, whole.position_checks[i].gain);
    }
    EXPECT_EQ(banded.passes.size(), whole.passes.size());
    EXPECT_EQ(banded.normals.model, whole.normals.model);
    EXPECT_EQ(banded.normals.shininess, whole.normals.shininess);
    EXPECT_EQ(banded.normals.ks, whole.normals.ks);
    ExpectSame(banded.normals.normals, whole.normals.normals, "normals");
    ExpectSame(banded.normals.albedo, whole.normals.albedo, "albedo");
    ExpectSame(banded.normals.specular, whole.normals.specular, "specular");
    ExpectSame(banded.normals.residual, whole.normals.residual, "residual");
    ExpectSame(banded.normals.model_map, whole.normals.model_map, "model map");
    ExpectSame(banded.height, whole.height, "height");
  }
}

}  // namespace
}  // namespace iphong::near
