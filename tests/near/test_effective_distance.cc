// The effective distance (near/effective_distance.h) on a capture read in bands of rows against
// the same on the whole capture: the same D, and every pixel's result bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "near/effective_distance.h"
#include "near/internal.h"
#include "near/near_scenes.h"

namespace iphong::near {
namespace {

using test_data::Dome;
using test_data::NearCapture;
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

// A matte sphere 36 pixels wide, seen orthographically, under a dome of 24 lights `sizes` object
// sizes away, their intensity scaled to light it alike at every distance.
NearScene SphereUnderDome(double sizes) {
  NearScene s;
  s.width = 44;
  s.height = 40;
  s.frame.perspective = false;
  s.frame.pixel_size = 2.8;  // mm: the sphere is 36 pixels wide
  s.lights = Dome(s.center, sizes * 2 * s.radius, 24, 2e4 * std::pow(2 * sizes / 3, 2));
  s.material.kd = Vec3d(0.7, 0.6, 0.5);
  return s;
}

// A matte sphere under a dome of 24 lights at 3 object sizes, seen orthographically and read
// with directions only (the case the effective distance is for), D chosen and D given: the
// choice's candidates and checks, the passes and every map are the same in bands as whole.
// Whether the choice keeps its D here is the position check's known tie on a sphere (points
// placed by their normals are the sphere): since the per-pixel test scales its leave-one-out
// error it refuses 107 px by 5.3 standard errors of a difference of 0.001 against a gain of 9.7
// (docs/guides/near-lights.md); at the D given the passes run either way.
TEST(EffectiveDistance, InBandsEqualsTheWholeBitForBit) {
  const NearScene s = SphereUnderDome(3);
  solve::PhotometricData data = RenderNearSphere(s).data;
  data.point_lights.clear();  // directions only
  data.perspective = false;

  for (const double given : {0.0, 6 * s.radius / s.frame.pixel_size}) {
    SCOPED_TRACE(given);
    EffectiveDistanceOptions options;
    options.distance_px = given;
    options.normals.plan_sample = 600;   // below the pixel count: a stride sample
    options.normals.model_sample = 200;  // the choice's cost, which dominates here
    const EffectiveDistanceResult whole = SolveEffectiveDistance(data, options);
    if (given > 0) {
      ASSERT_FALSE(whole.passes.empty());
    } else {
      ASSERT_FALSE(whole.scored.empty());
      ASSERT_FALSE(whole.position_checks.empty());  // a D was proposed and checked
    }

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
      EXPECT_EQ(banded.centre_behind_px, whole.centre_behind_px);
      ASSERT_EQ(banded.scored.size(), whole.scored.size());
      for (std::size_t i = 0; i < whole.scored.size(); ++i) {
        EXPECT_EQ(banded.scored[i].heldout_cost, whole.scored[i].heldout_cost);
      }
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
}

// Mean angle to the ground truth (degrees) over the pixels `r` solved.
double MeanErrorDeg(const solve::NormalResult& r, const ImageF& truth) {
  double sum = 0;
  int n = 0;
  for (std::size_t p = 0; p < r.residual.pixels.size(); ++p) {
    if (r.residual.pixels[p] < 0 || truth.pixels[3 * p + 2] == 0) continue;
    double dot = 0;
    for (int c = 0; c < 3; ++c) dot += r.normals.pixels[3 * p + c] * truth.pixels[3 * p + c];
    sum += std::acos(std::clamp(dot, -1.0, 1.0)) * 180 / M_PI;
    ++n;
  }
  return sum / n;
}

// A matte sphere under a dome of 12 lights at 3 object sizes, read with directions only and
// solved with distant lights and the foil (the normal-centred lobe): the distant solve's per-pixel
// test hands part of the sphere to Lambert, which lacks the fall-off the foil carries; the refit
// gives every pixel the foil, closer to the truth, the same in bands.
TEST(EffectiveDistance, TheFoilAtDistantLightsIsRefittedAtEveryPixel) {
  NearScene s;
  s.width = 44;
  s.height = 40;
  s.frame.perspective = false;
  s.frame.pixel_size = 2.8;
  s.lights = Dome(s.center, 3 * s.radius, 12, 2e4);
  s.material.kd = Vec3d(0.7, 0.6, 0.5);
  const NearCapture capture = RenderNearSphere(s);
  solve::PhotometricData data = capture.data;
  data.point_lights.clear();
  data.perspective = false;

  EffectiveDistanceOptions options;
  options.distance_px = std::numeric_limits<double>::infinity();
  options.normals.model = reflectance::Lobe::kNormalCentred;
  options.normals.plan_sample = 600;
  options.normals.model_sample = 200;
  const EffectiveDistanceResult whole = SolveEffectiveDistance(data, options);
  ASSERT_EQ(whole.distant.model, reflectance::Lobe::kNormalCentred);
  std::size_t lambert = 0;
  for (float v : whole.distant.model_map.pixels) lambert += v == 0;
  ASSERT_GT(lambert, 0u) << "the per-pixel test gave no pixel to Lambert: nothing to undo";
  EXPECT_TRUE(whole.foil_refit);
  EXPECT_TRUE(whole.normals.model_map.pixels.empty());
  const double before = MeanErrorDeg(whole.distant, capture.normal_gt);
  const double after = MeanErrorDeg(whole.normals, capture.normal_gt);
  std::printf("distant solve %.3f deg (%zu pixels Lambert), refitted with the foil %.3f deg\n",
              before, lambert, after);
  // Measured 2.63 -> 2.23 while the per-pixel test took its leave-one-out error as stated;
  // 2.19 -> 2.08 since it scales it (LeaveOneOutErrorScale), which left 18 pixels to Lambert;
  // 2.11 -> 2.05 since its folds search near the all-lights answer (8 pixels).
  EXPECT_LT(after, 0.98 * before);

  solve::BandSource source;
  source.width = data.width;
  source.height = data.height;
  source.masked_pixels = data.pixel_count();
  source.read = [&](int y0, int y1, bool) { return Rows(data, y0, y1); };
  const EffectiveDistanceResult banded = SolveEffectiveDistanceInBands(source, 7, options);
  EXPECT_TRUE(banded.foil_refit);
  EXPECT_EQ(banded.normals.ks, whole.normals.ks);
  ExpectSame(banded.normals.normals, whole.normals.normals, "normals");
  ExpectSame(banded.normals.specular, whole.normals.specular, "specular");
}

// The lights' move as a point sees them, in closed form: one isotropic point light r away along
// the axis; a point moved by t toward it turns nothing and brightens it by (r/(r − t))², ln of
// that is 2 ln(r/(r − t)); moved by t across, the light turns by atan(t/r) and dims by
// r²/(r² + t²). An LED's factor (−a·L)^μ enters the irradiance too.
TEST(EffectiveDistance, LightsMovedInClosedForm) {
  solve::PhotometricData data;
  data.images = 1;
  data.pixels = {0};
  const double r = 100, t = 3;
  data.point_lights = {reflectance::Light::Point(Vec3d(0, 0, 0), Rgb(2, 2, 2), true)};
  data.points_cam = {Vec3d(0, 0, r)};
  const double deg = 180 / M_PI;
  EXPECT_NEAR(internal::LightsMovedDeg(data, {Vec3d(0, 0, r - t)}), 2 * std::log(r / (r - t)) * deg,
              1e-9);
  EXPECT_NEAR(internal::LightsMovedDeg(data, {Vec3d(t, 0, r)}),
              (std::atan(t / r) + std::log((r * r + t * t) / (r * r))) * deg, 1e-9);
  // The larger of two lights; a light the point leaves (behind an LED) counts a right angle.
  data.point_lights.push_back(
      reflectance::Light::Led(Vec3d(0, 0, 2 * r), Rgb(1, 1, 1), Vec3d(0, 0, -1), 1));
  EXPECT_NEAR(internal::LightsMovedDeg(data, {Vec3d(0, 0, r - t)}),
              std::max(2 * std::log(r / (r - t)), 2 * std::log((r + t) / r)) * deg, 1e-9);
  EXPECT_NEAR(internal::LightsMovedDeg(data, {Vec3d(0, 0, 2 * r + 1)}), 90, 1e-9);
  EXPECT_EQ(internal::LightsMovedDeg(data, {Vec3d(0, 0, r)}), 0);
  EXPECT_THROW(internal::LightsMovedDeg(data, {}), std::invalid_argument);

  // Between two sets of lights, each seen from its own points: a light moved from r to 2r along
  // the same line dims by 4 and turns nothing; one moved by r across turns by 45° and dims by 2.
  // The same as moving the point the other way.
  solve::PhotometricData near = data, far = data;
  near.point_lights.resize(1);
  far.point_lights = {reflectance::Light::Point(Vec3d(0, 0, -r), Rgb(2, 2, 2), true)};
  EXPECT_NEAR(internal::LightsChangedDeg(near, far), std::log(4.0) * deg, 1e-9);
  far.point_lights = {reflectance::Light::Point(Vec3d(r, 0, 0), Rgb(2, 2, 2), true)};
  EXPECT_NEAR(internal::LightsChangedDeg(near, far), (M_PI / 4 + std::log(2.0)) * deg, 1e-9);
  EXPECT_NEAR(internal::LightsChangedDeg(near, far),
              internal::LightsMovedDeg(near, {Vec3d(-r, 0, r)}), 1e-9);
  EXPECT_EQ(internal::LightsChangedDeg(near, near), 0);
  EXPECT_THROW(internal::LightsChangedDeg(near, data), std::invalid_argument);  // 1 light, 2
}

// The choice's surface: a hemisphere of radius 300 on a 640² grid (282 600 pixels, over 2^18) is
// integrated on 2×2 blocks and comes back with the same mean and within 0.05 px of the full
// integration's depths (0.023 px measured) over the middle 90 % of its radius, where the grazing
// rim moves by a few pixels; a quarter of it (under 2^18) is integrated pixel by pixel.
TEST(EffectiveDistance, TheChoicesSurfaceOfALargeCaptureIsIntegratedOnBlocks) {
  const int side = 640;
  const double radius = 300;
  auto make = [&](double reach) {
    solve::PhotometricData data;
    data.width = data.height = side;
    solve::NormalResult r;
    r.normals = ImageF(side, side, 3, 0.0f);
    for (int row = 0; row < side; ++row) {
      for (int col = 0; col < side; ++col) {
        const double x = col + 0.5 - side / 2.0, y = side / 2.0 - row - 0.5;
        if (x * x + y * y >= reach * reach) continue;
        const double z = std::sqrt(radius * radius - x * x - y * y);
        float* n = r.normals.at(col, row);
        n[0] = static_cast<float>(x / radius), n[1] = static_cast<float>(y / radius);
        n[2] = static_cast<float>(z / radius);
        data.pixels.push_back(row * side + col);
      }
    }
    return std::make_pair(data, r);
  };
  const geometry::HeightMapFrame frame;  // orthographic, a pixel per unit
  for (double reach : {radius - 1, radius / 2}) {
    SCOPED_TRACE(reach);
    const auto [data, r] = make(reach);
    const std::vector<double> zero(data.pixel_count(), 0.0);
    const std::vector<double> full = internal::IntegratedDepth(r, data, frame, zero, 0.05, 2);
    const std::vector<double> choice =
        internal::IntegratedDepth(r, data, frame, zero, 0.05, 2, internal::kChoiceSurfacePixels);
    double offset = 0;  // both have the same mean (0 here), blocks or not
    for (std::size_t i = 0; i < data.pixel_count(); ++i) offset += choice[i] - full[i];
    offset /= static_cast<double>(data.pixel_count());
    EXPECT_NEAR(offset, 0, 1e-3);
    double worst = 0, moved = 0;
    for (std::size_t i = 0; i < data.pixel_count(); ++i) {
      const double x = data.pixels[i] % side + 0.5 - side / 2.0;
      const double y = side / 2.0 - data.pixels[i] / side - 0.5;
      const double e = std::abs(choice[i] - full[i] - offset);
      moved = std::max(moved, e);
      if (std::hypot(x, y) < 0.9 * reach) worst = std::max(worst, e);
    }
    if (data.pixel_count() > internal::kChoiceSurfacePixels) {
      EXPECT_GT(moved, 1e-3);  // blocks, not the pixels
      EXPECT_LT(worst, 0.05);
    } else {
      EXPECT_EQ(moved, 0);
    }
  }
}

// The near passes stop once the lights, as the new surface's points see them, moved by less than
// the tolerance: the next pass would refit every pixel under the lights it was fitted under. A
// sphere under a dome at 12 object sizes, D given: one pass (its lights moved 0.06°, its normals
// 0.1–0.2°), and further passes change the error by under a hundredth of a degree (measured
// 0.013° against 0.012° after three). At 1.5 object sizes the first pass's lights move by
// tenths of a degree (0.78°), and the passes go on.
TEST(EffectiveDistance, PassesStopOnceTheLightsStandStill) {
  for (const double sizes : {12.0, 1.5}) {
    SCOPED_TRACE(sizes);
    const NearScene s = SphereUnderDome(sizes);
    const NearCapture capture = RenderNearSphere(s);
    solve::PhotometricData data = capture.data;
    data.point_lights.clear();  // directions only
    data.perspective = false;

    EffectiveDistanceOptions options;
    options.distance_px = sizes * 2 * s.radius / s.frame.pixel_size;
    options.normals.plan_sample = 600;
    options.normals.model_sample = 200;
    const EffectiveDistanceResult stopped = SolveEffectiveDistance(data, options);
    ASSERT_FALSE(stopped.passes.empty());
    const double error = MeanErrorDeg(stopped.normals, capture.normal_gt);
    std::printf(
        "%.1f object sizes: %zu passes, lights moved %.4f deg after the first, normals "
        "%.3f deg; %.3f deg off\n",
        sizes, stopped.passes.size(), stopped.passes[0].lights_moved_deg,
        stopped.passes[0].change_deg, error);
    if (sizes < 10) {
      EXPECT_GT(stopped.passes[0].lights_moved_deg, 0.1);
      EXPECT_GE(stopped.passes.size(), 2u);
      continue;
    }
    EXPECT_EQ(stopped.passes.size(), 1u);
    EXPECT_GT(stopped.passes[0].change_deg, 0.1);  // the normals' change alone would go on
    EXPECT_LT(stopped.passes[0].lights_moved_deg, EffectiveDistanceOptions().tolerance_deg);
    options.tolerance_deg = 1e-9;
    const EffectiveDistanceResult more = SolveEffectiveDistance(data, options);
    ASSERT_EQ(more.passes.size(), 3u);
    const double error_more = MeanErrorDeg(more.normals, capture.normal_gt);
    std::printf("  after three passes %.3f deg off\n", error_more);
    EXPECT_NEAR(error, error_more, 0.01);
  }
}

// A proposal that stands made its surface with the model chosen again under its lights: that
// refinement of every pixel is the first near pass, not a step before the passes. Counted through
// the capture's refine: one per proposal checked, plus one per pass after the first (before, one
// per pass as well). A Phong sphere under a dome of 24 lights at 3 object sizes, read with
// directions only: D = 132 px stands (107 true), one proposal, then passes at it and at the D
// chosen again on their surface (RefineDistance).
// A Phong sphere (ks 0.4, n 30) under a dome of 24 lights at 3 object sizes, read with directions
// only, and the options both tests below solve it with.
struct GlossyDome {
  NearScene s = SphereUnderDome(3);
  NearCapture scene;
  solve::PhotometricData data;
  EffectiveDistanceOptions options;
  GlossyDome() {
    s.material.ks = Vec3d(0.4, 0.4, 0.4);
    s.material.shininess = 30;
    scene = RenderNearSphere(s);
    data = scene.data;
    data.point_lights.clear();  // directions only
    data.perspective = false;
    options.normals.plan_sample = 600;
    options.normals.model_sample = 200;
    // Phong asked for: left to choose, this sphere takes the foil, whose proposals are made by
    // the diffuse test's Lambert instead.
    options.normals.model = reflectance::Lobe::kPhong;
    options.normals.choose_model = false;
  }
};

TEST(EffectiveDistance, AnAcceptedProposalIsTheFirstPass) {
  GlossyDome dome;
  const NearCapture& scene = dome.scene;
  solve::PhotometricData& data = dome.data;
  const EffectiveDistanceOptions& options = dome.options;

  // SolveEffectiveDistance's steps, its capture's refinements counted.
  const std::vector<std::size_t> plan_sample =
      solve::PlanSampleIndices(data.pixel_count(), options.normals.plan_sample);
  const solve::NormalPlan plan =
      solve::PlanNormals(solve::SubsetObservations(data, plan_sample), options.normals);
  ASSERT_NE(plan.options.model, reflectance::Lobe::kNormalCentred) << "a foil plan: no first pass";
  solve::NormalResult distant = solve::SolveNormalsWithPlan(data, plan);
  {
    std::vector<Vec3f> sample_ks;
    solve::AppendSampleSpecular(distant, data, plan_sample, sample_ks);
    solve::FinishNormals(distant, plan, sample_ks);
  }
  int refinements = 0;
  DistanceCapture capture;
  capture.layout = &data;
  capture.observations = [&](const std::vector<std::vector<std::size_t>>& sets) {
    std::vector<solve::PhotometricData> out;
    for (const auto& indices : sets) out.push_back(solve::SubsetObservations(data, indices));
    return out;
  };
  capture.refine = [&](const solve::PhotometricData& lights, const solve::NormalPlan& by,
                       const solve::NormalResult& previous) {
    ++refinements;
    solve::PhotometricData with = data;
    with.point_lights = lights.point_lights;
    with.light_directions = lights.light_directions;
    with.light_intensities = lights.light_intensities;
    with.points_cam = lights.points_cam;
    return solve::RefineNormalsWithPlan(with, by, previous);
  };
  const EffectiveDistanceResult r = ContinueEffectiveDistance(capture, plan, distant, options);
  ASSERT_TRUE(std::isfinite(r.distance_px)) << "no D stood: nothing to count";
  ASSERT_FALSE(r.passes.empty());
  std::vector<double> proposals;
  for (const PositionCheck& c : r.position_checks) {
    if (std::find(proposals.begin(), proposals.end(), c.distance_px) == proposals.end()) {
      proposals.push_back(c.distance_px);
    }
  }
  std::printf("D %.1f px, %zu proposal(s), %zu pass(es), %d refinements; %.3f deg off\n",
              r.distance_px, proposals.size(), r.passes.size(), refinements,
              MeanErrorDeg(r.normals, scene.normal_gt));
  EXPECT_EQ(refinements, static_cast<int>(proposals.size() + r.passes.size()) - 1);
  EXPECT_EQ(r.passes[0].distance, proposals.back());  // the proposal that stood is checked last
  // The same steps as the library's own capture, bit for bit.
  const EffectiveDistanceResult library = SolveEffectiveDistance(data, options);
  EXPECT_EQ(library.distance_px, r.distance_px);
  EXPECT_EQ(library.passes.size(), r.passes.size());
  ExpectSame(library.normals.normals, r.normals.normals, "normals");
}

// The first choice of D is made on the surface the distant solve integrated, whose normals the
// near lights' fall-off bent; on this sphere (the test above) it sets the lights a quarter too far
// (132 px for 107). Chosen again on the surface the passes made, D comes within a few per cent
// and the normals follow.
TEST(EffectiveDistance, TheDistanceIsChosenAgainOnThePassesSurface) {
  GlossyDome dome;
  const NearCapture& scene = dome.scene;
  const solve::PhotometricData& data = dome.data;
  EffectiveDistanceOptions& options = dome.options;
  const double true_px = 3 * 2 * dome.s.radius / dome.s.frame.pixel_size;
  options.distance_rounds = 0;
  const EffectiveDistanceResult first = SolveEffectiveDistance(data, options);
  options.distance_rounds = EffectiveDistanceOptions().distance_rounds;  // the default
  ASSERT_GT(options.distance_rounds, 0);
  const EffectiveDistanceResult again = SolveEffectiveDistance(data, options);
  const double first_error = MeanErrorDeg(first.normals, scene.normal_gt);
  const double again_error = MeanErrorDeg(again.normals, scene.normal_gt);
  std::printf("D %.1f px (%.3f deg off), chosen again %.1f px (%.3f deg off), true %.1f px\n",
              first.distance_px, first_error, again.distance_px, again_error, true_px);
  ASSERT_TRUE(std::isfinite(first.distance_px));
  EXPECT_GT(first.distance_px, 1.15 * true_px);  // the bias the rounds are for
  EXPECT_NEAR(again.distance_px, true_px, 0.05 * true_px);
  EXPECT_LT(again_error, 0.6 * first_error);
  // Every candidate of the rounds is recorded, after the first choice's.
  const auto is_round = [](const DistanceCandidate& c) {
    return c.criterion.find("again on the near surface") != std::string::npos;
  };
  EXPECT_EQ(std::count_if(first.scored.begin(), first.scored.end(), is_round), 0);
  EXPECT_GT(std::count_if(again.scored.begin(), again.scored.end(), is_round), 3);
  EXPECT_GT(again.passes.size(), first.passes.size());
  EXPECT_EQ(again.passes.back().distance, again.distance_px);
}

}  // namespace
}  // namespace iphong::near
