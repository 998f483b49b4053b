// Which reading of the recorded values the data support (solve/reading_check.h): a sphere's
// photos stored display-encoded (the sRGB curve, 8-bit codes) and stored linear, each compared
// with its values decoded by the curve. The curve is spelled here, not taken from io/.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "solve/reading_check.h"
#include "synthetic_spheres.h"

namespace iphong::solve {
namespace {

using test_data::MakeSphereData;
using test_data::Synthetic;

double Encode(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
}
double Decode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

PhotometricData Stored(const PhotometricData& linear, bool display_encoded) {
  PhotometricData out = linear;
  for (float& v : out.values) {
    v = static_cast<float>(
        std::round((display_encoded ? Encode(v) : std::clamp(v, 0.0f, 1.0f)) * 255) / 255);
  }
  return out;
}

// Measured here (the sRGB reading's held-out log-likelihood, standard errors): matte, encoded
// photos +203, linear ones −339; glossy (Phong n 24) +47 and −42. On the real photos iphong
// reads as linear (DiLiGenT's 8-bit crops and 16-bit cat, UW cat and gray) −9.6 to −61.
TEST(ReadingCheck, DisplayEncodedPhotosAreToldFromLinearOnes) {
  for (const double ks : {0.0, 0.35}) {
    SCOPED_TRACE(ks);
    reflectance::Material m;
    m.kd = Vec3d(0.7, 0.56, 0.42);
    m.ks = Vec3d::Constant(ks);
    m.shininess = 24;
    const Synthetic s = MakeSphereData(m, 24, 0.0, Vec3d::Zero(), 64);
    ModelChoiceSettings settings;
    for (const bool encoded : {true, false}) {
      SCOPED_TRACE(encoded);
      const ReadingComparison c = CompareReadings(Stored(s.data, encoded), Decode, settings);
      EXPECT_GT(c.pixels, 500u);
      if (encoded) {
        EXPECT_GT(c.gain, 5 * c.gain_error);
        EXPECT_LT(c.cost_reread, c.cost_as_given);
      } else {
        EXPECT_LT(c.gain, -5 * c.gain_error);
      }
    }
  }
}

TEST(ReadingCheck, FewImagesAreRefused) {
  reflectance::Material m;
  const Synthetic s = MakeSphereData(m, 5, 0.0, Vec3d::Zero(), 32);
  EXPECT_THROW(CompareReadings(s.data, Decode, ModelChoiceSettings{}), std::invalid_argument);
}

}  // namespace
}  // namespace iphong::solve
