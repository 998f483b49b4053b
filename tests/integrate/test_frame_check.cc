// The frame check (integrate/frame_check.h) on analytic normal fields: a surface with mixed
// second derivatives inside a silhouette and cut by the image border, read in each of the eight
// frames of the image plane.
#include <gtest/gtest.h>

#include <cmath>

#include "integrate/frame_check.h"

namespace iphong::integrate {
namespace {

// A lumpy dome (three off-centre bumps on an ellipsoid) on a w×h grid. `silhouette`: the dome's
// occluding contour is the mask's edge (normals there turn to the image plane); otherwise the
// field is cut out of the dome's top by the image border (a crop: no contour).
ImageF LumpyField(int w, int h, bool silhouette, Mask* mask) {
  *mask = Mask(w, h, false);
  ImageF n(w, h, 3, 0.0f);
  const double a = silhouette ? 0.46 * w : 1.3 * w, b = silhouette ? 0.40 * h : 1.3 * h;
  const double bumps[3][3] = {{0.15, 0.2, 0.12}, {-0.2, -0.1, 0.1}, {0.05, -0.25, 0.08}};
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const double x = (c + 0.5 - 0.5 * w), y = (0.5 * h - r - 0.5);
      const double e = 1 - (x / a) * (x / a) - (y / b) * (y / b);
      if (e <= 0.002) continue;
      // z = R sqrt(e) + Σ bumps; R = the mean of the axes so the dome is round-ish.
      const double R = 0.5 * (a + b);
      double p = -R * x / (a * a * std::sqrt(e)), q = -R * y / (b * b * std::sqrt(e));
      for (const auto& k : bumps) {
        const double cx = k[0] * w, cy = k[1] * h, s = k[2] * w, height = 0.6 * s;
        const double g = height * std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (s * s));
        p += -2 * (x - cx) / (s * s) * g, q += -2 * (y - cy) / (s * s) * g;
      }
      const Vec3d v = Vec3d(-p, -q, 1).normalized();
      float* o = n.at(c, r);
      o[0] = float(v.x()), o[1] = float(v.y()), o[2] = float(v.z());
      mask->inside[std::size_t(r) * w + c] = 1;
    }
  }
  return n;
}

ImageF Read(const ImageF& field, PlaneReading reading) {
  ImageF out = field;
  for (std::size_t p = 0; p < out.pixel_count(); ++p) {
    float* v = out.pixels.data() + 3 * p;
    const Vec3f t = ApplyReading(reading, Vec3f(v[0], v[1], v[2]));
    v[0] = t.x(), v[1] = t.y(), v[2] = t.z();
  }
  return out;
}

// The reading that undoes `reading` (the group's inverse: the rotations swap, the rest are
// their own).
PlaneReading Inverse(PlaneReading reading) {
  if (reading == PlaneReading::kRotated90) return PlaneReading::kRotated270;
  if (reading == PlaneReading::kRotated270) return PlaneReading::kRotated90;
  return reading;
}

TEST(FrameCheck, ReadingsAreTheEightSymmetriesOfThePlane) {
  const Vec3d v(0.3, -0.5, 0.7);
  for (int i = 0; i < kPlaneReadings; ++i) {
    const PlaneReading r = PlaneReading(i);
    const Vec3d t = ApplyReading(r, v);
    EXPECT_DOUBLE_EQ(t.z(), v.z()) << PlaneReadingName(r);
    EXPECT_NEAR(t.norm(), v.norm(), 1e-15);
    EXPECT_TRUE(ApplyReading(Inverse(r), t).isApprox(v)) << PlaneReadingName(r);
    for (int j = 0; j < i; ++j) EXPECT_FALSE(ApplyReading(PlaneReading(j), v).isApprox(t));
  }
}

TEST(FrameCheck, ASilhouettedFieldInAnyOtherFrameIsNamedAndTheRightOneIsQuiet) {
  Mask mask;
  const ImageF field = LumpyField(160, 120, true, &mask);
  const FrameCheckResult right = CheckNormalFrame(field, mask);
  EXPECT_EQ(right.better, PlaneReading::kAsGiven) << right.message;
  EXPECT_TRUE(right.message.empty());
  EXPECT_GT(right.silhouette_pixels, 100u);
  EXPECT_GT(right.scores[0].silhouette_cos, 0.9);
  EXPECT_LT(right.scores[0].consistency_deg, 1.0);
  for (int i = 1; i < kPlaneReadings; ++i) {
    const PlaneReading wrong = PlaneReading(i);
    const FrameCheckResult r = CheckNormalFrame(Read(field, wrong), mask);
    // The field in frame T reads right with T's inverse, and the message says so.
    EXPECT_EQ(r.better, Inverse(wrong)) << PlaneReadingName(wrong);
    EXPECT_NE(r.message.find(PlaneReadingName(Inverse(wrong))), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("silhouette"), std::string::npos) << r.message;
    // A half turn is the same surface upside down: the same distance from it.
    const double half_turn = r.scores[int(Inverse(wrong))].consistency_deg;
    if (wrong == PlaneReading::kXYNegated) {
      EXPECT_NEAR(r.scores[0].consistency_deg, half_turn, 1e-6);
    } else {
      EXPECT_GT(r.scores[0].consistency_deg, 1.3 * half_turn) << PlaneReadingName(wrong);
    }
  }
}

TEST(FrameCheck, WithoutASilhouetteIntegrabilityNamesTheFrameUpToAHalfTurn) {
  Mask mask;
  const ImageF field = LumpyField(150, 130, false, &mask);
  ASSERT_EQ(mask.count(), mask.inside.size());  // a crop: the mask is the whole image
  const FrameCheckResult right = CheckNormalFrame(field, mask);
  EXPECT_EQ(right.silhouette_pixels, 0u);  // the image border is not a contour
  EXPECT_TRUE(std::isnan(right.scores[0].silhouette_cos));
  EXPECT_TRUE(right.message.empty()) << right.message;
  for (int i = 1; i < kPlaneReadings; ++i) {
    const PlaneReading wrong = PlaneReading(i);
    const FrameCheckResult r = CheckNormalFrame(Read(field, wrong), mask);
    if (wrong == PlaneReading::kXYNegated) {
      EXPECT_TRUE(r.message.empty()) << r.message;  // the surface upside down: integrable
      continue;
    }
    // Either the inverse or the inverse after a half turn: the two make the same surface.
    const Vec3d probe(0.3, -0.5, 0.7);
    const Vec3d want = ApplyReading(Inverse(wrong), probe);
    const Vec3d got = ApplyReading(r.better, probe);
    EXPECT_TRUE(got.isApprox(want) || got.isApprox(Vec3d(-want.x(), -want.y(), want.z())))
        << PlaneReadingName(wrong) << " -> " << PlaneReadingName(r.better);
    EXPECT_NE(r.message.find("from a surface"), std::string::npos) << r.message;
  }
}

TEST(FrameCheck, FlatOrTinyFieldsSayNothing) {
  // A plane is integrable in every frame: no reading is better.
  ImageF plane(64, 64, 3, 0.0f);
  for (std::size_t p = 0; p < plane.pixel_count(); ++p) plane.pixels[3 * p + 2] = 1;
  const FrameCheckResult r = CheckNormalFrame(plane, Mask(64, 64, true));
  EXPECT_TRUE(r.message.empty()) << r.message;
  // Three pixels: neither cue has enough to speak.
  Mask few(64, 64, false);
  few.inside[0] = few.inside[1] = few.inside[64] = 1;
  EXPECT_TRUE(CheckNormalFrame(plane, few).message.empty());
}

TEST(FrameCheck, BadInputIsRefused) {
  ImageF n(8, 8, 3, 0.0f);
  EXPECT_THROW(CheckNormalFrame(n, Mask(9, 8, true)), std::invalid_argument);
  n.pixels[5] = NAN;
  EXPECT_THROW(CheckNormalFrame(n, Mask(8, 8, true)), std::invalid_argument);
  FrameCheckOptions bad;
  bad.integrability_ratio = 0.5;
  EXPECT_FALSE(bad.Validate().empty());
  EXPECT_THROW(CheckNormalFrame(ImageF(8, 8, 3, 0.0f), Mask(8, 8, true), bad),
               std::invalid_argument);
}

}  // namespace
}  // namespace iphong::integrate
