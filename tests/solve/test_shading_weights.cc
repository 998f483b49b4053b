// The fit's weights by N·L (shading_weights.h) on spheres shaded by hand, independently of the
// renderer: an exact cosine leaves every weight near 1 and the normals as they were; a shading
// darkened toward the terminator, as a mesh renderer's self-shadowing darkens it, is weighed down
// there and its normals come back closer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "solve/normals.h"
#include "solve/shading_weights.h"

namespace iphong::solve {
namespace {

struct HandSphere {
  PhotometricData data;
  std::vector<Vec3d> normal;  // per masked pixel
};

// A sphere seen from above under 48 lights of a hemisphere cap (elevations 30°–90°), shading
// ρ · s(N·L): s(c) = c, or with `terminator` (c − τ)/(1 − τ) above τ and 0 below.
HandSphere Sphere(double terminator) {
  const int size = 64, k = 48;
  std::vector<Vec3d> lights;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int j = 0; j < k; ++j) {
    const double z = 1 - 0.5 * (j + 0.5) / k, r = std::sqrt(1 - z * z);
    lights.emplace_back(r * std::cos(golden * j), r * std::sin(golden * j), z);
  }
  std::vector<std::vector<float>> images(k, std::vector<float>(3 * size * size, 0.0f));
  Mask mask(size, size, false);
  HandSphere s;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size * 2 - 1, v = 1 - (y + 0.5) / size * 2;
      if (u * u + v * v > 0.9 * 0.9) continue;
      const Vec3d n(u, v, std::sqrt(1 - u * u - v * v));
      mask.inside[y * size + x] = 1;
      for (int j = 0; j < k; ++j) {
        const double c = n.dot(lights[j]);
        const double shade =
            terminator > 0 ? std::max(0.0, (c - terminator) / (1 - terminator)) : std::max(0.0, c);
        for (int ch = 0; ch < 3; ++ch)
          images[j][3 * (y * size + x) + ch] = static_cast<float>(0.6 * shade);
      }
    }
  }
  std::vector<const float*> pointers;
  for (const auto& image : images) pointers.push_back(image.data());
  s.data =
      GatherObservations(pointers, size, size, mask, lights, std::vector<Vec3d>(k, Vec3d::Ones()));
  for (int i : s.data.pixels) {
    const double u = (i % size + 0.5) / size * 2 - 1, v = 1 - (i / size + 0.5) / size * 2;
    s.normal.emplace_back(u, v, std::sqrt(1 - u * u - v * v));
  }
  return s;
}

double MeanErrorDeg(const NormalResult& r, const HandSphere& s) {
  double sum = 0;
  for (std::size_t i = 0; i < s.normal.size(); ++i) {
    const std::size_t p = static_cast<std::size_t>(s.data.pixels[i]);
    const Vec3d n(r.normals.pixels[3 * p], r.normals.pixels[3 * p + 1],
                  r.normals.pixels[3 * p + 2]);
    sum += std::acos(std::clamp(n.normalized().dot(s.normal[i]), -1.0, 1.0)) * 180 / M_PI;
  }
  return sum / s.normal.size();
}

// The sphere solved with the weights by N·L (first) and without (second).
std::pair<NormalResult, NormalResult> WeightedAndPlain(const HandSphere& s) {
  NormalOptions on, off;
  off.weigh_by_shading = false;
  return {EstimateNormals(s.data, on), EstimateNormals(s.data, off)};
}

TEST(ShadingWeights, BandsAndValidation) {
  ShadingWeights w{{0.3, 0.6, 1.0}, {0.25, 0.5, 1.0}, {-0.2, 0.0, 0.0}};
  EXPECT_EQ(w.At(0.1), 0.25);
  EXPECT_EQ(w.At(0.3), 0.5);  // an edge belongs to the band above it
  EXPECT_EQ(w.At(0.99), 1.0);
  EXPECT_EQ(w.At(1.5), 1.0);
  EXPECT_EQ(w.OffsetAt(0.1), -0.2);
  EXPECT_EQ(w.OffsetAt(0.3), 0.0);
  EXPECT_EQ(w.Validate(), "");
  EXPECT_EQ((ShadingWeights{{0.3, 1.0}, {0.5, 1.0}, {}}).OffsetAt(0.1), 0.0);  // none given
  EXPECT_NE((ShadingWeights{{0.3, 1.0}, {0.5, 1.0}, {0.1}}).Validate(), "");
  EXPECT_NE((ShadingWeights{{0.3, 1.0}, {0.5, 1.0}, {NAN, 0.0}}).Validate(), "");
  EXPECT_NE((ShadingWeights{{0.3, 1.0}, {0.5, 1.0}, {-1.5, 0.0}}).Validate(), "");
  EXPECT_NE((ShadingWeights{{0.3}, {0.5, 1.0}, {}}).Validate(), "");
  EXPECT_NE((ShadingWeights{{0.6, 0.3}, {0.5, 1.0}, {}}).Validate(), "");
  EXPECT_NE((ShadingWeights{{0.3, 1.0}, {0.0, 1.0}, {}}).Validate(), "");
  NormalOptions o;
  o.shading_weights = ShadingWeights{{0.3, 1.0}, {1.5, 1.0}, {}};
  EXPECT_NE(o.Validate(), "");
}

TEST(ShadingWeights, AnExactCosineKeepsEveryWeightAndNormal) {
  const HandSphere s = Sphere(0);
  const auto [weighted, plain] = WeightedAndPlain(s);
  const ShadingMisfit& m = weighted.model_choice.shading;
  ASSERT_EQ(m.weights.weight.size(), static_cast<std::size_t>(kShadingBands));
  for (double w : m.weights.weight) EXPECT_GT(w, 0.95);
  EXPECT_TRUE(plain.model_choice.shading.weights.empty());
  EXPECT_LT(MeanErrorDeg(weighted, s), 0.05);
  EXPECT_LT(std::abs(MeanErrorDeg(weighted, s) - MeanErrorDeg(plain, s)), 0.01);
}

TEST(ShadingWeights, ATerminatorDarkeningIsWeighedDownAndTheNormalsImprove) {
  const HandSphere s = Sphere(0.15);
  const auto [weighted, plain] = WeightedAndPlain(s);
  const ShadingMisfit& m = weighted.model_choice.shading;
  ASSERT_EQ(m.weights.weight.size(), static_cast<std::size_t>(kShadingBands));
  EXPECT_LT(m.weights.weight[0], 0.5);
  EXPECT_LT(m.bias[0], 0);  // darker than predicted toward the terminator
  for (int b = kShadingBands / 2; b < kShadingBands; ++b) EXPECT_EQ(m.weights.weight[b], 1.0);
  const double with = MeanErrorDeg(weighted, s), without = MeanErrorDeg(plain, s);
  std::printf("terminator 0.15: mean error %.3f deg weighted, %.3f unweighted, %d rounds\n", with,
              without, m.rounds);
  // Measured: 4.26° against 6.37° (5.61° with the weights alone, below; the weights settle after
  // 5 rounds; the rendered bunny of ../shared/data goes from 3.92° to 1.79°).
  EXPECT_LT(with, 0.92 * without);
}

// What the settled weights leave of the terminator's bias is taken off the weighted bands'
// observations (ShadingWeights::offset); the same plan without the offsets is the comparison.
TEST(ShadingWeights, TheBiasTheWeightsLeaveIsTakenOff) {
  const HandSphere s = Sphere(0.15);
  const NormalPlan plan = PlanNormals(s.data, NormalOptions{});
  const ShadingMisfit& m = plan.model_choice.shading;
  const std::vector<double>& offset = plan.options.shading_weights.offset;
  ASSERT_EQ(offset.size(), static_cast<std::size_t>(kShadingBands));
  // The fixed point lies beyond the first measurement, which the normals had absorbed part of.
  EXPECT_LT(offset[0], m.bias[0]);
  EXPECT_LT(m.bias[0], 0);
  for (int b = kShadingBands / 2; b < kShadingBands; ++b) EXPECT_EQ(offset[b], 0.0);
  NormalPlan weights_only = plan;
  weights_only.options.shading_weights.offset.clear();
  const double with = MeanErrorDeg(SolveNormalsWithPlan(s.data, plan), s);
  const double without = MeanErrorDeg(SolveNormalsWithPlan(s.data, weights_only), s);
  std::printf("terminator 0.15: mean error %.3f deg with the offsets, %.3f with weights only\n",
              with, without);
  EXPECT_LT(with, 0.9 * without);
}

// The offsets are the bias measured at the normals they place, iterated to that fixed point; the
// first measurement (at the weighted fit's normals, offset by the settled weights' bias) is the
// comparison: the same plan with the offsets of its first round.
TEST(ShadingWeights, TheOffsetsAreTheBiasAtTheNormalsTheyPlace) {
  const HandSphere s = Sphere(0.15);
  const NormalPlan plan = PlanNormals(s.data, NormalOptions{});
  const ShadingMisfit& m = plan.model_choice.shading;
  EXPECT_GT(m.offset_rounds, 2);
  EXPECT_LT(m.offset_rounds, kOffsetRounds);  // settled, not cut off
  NormalPlan first = plan;
  for (int b = 0; b < kShadingBands; ++b) {
    first.options.shading_weights.offset[b] = b < kShadingBands / 2 ? m.bias[b] : 0.0;
  }
  const double fixed = MeanErrorDeg(SolveNormalsWithPlan(s.data, plan), s);
  const double once = MeanErrorDeg(SolveNormalsWithPlan(s.data, first), s);
  std::printf(
      "terminator 0.15: mean error %.3f deg at the fixed point (%d rounds), %.3f after "
      "one\n",
      fixed, m.offset_rounds, once);
  EXPECT_LT(fixed, 0.9 * once);
}

}  // namespace
}  // namespace iphong::solve
