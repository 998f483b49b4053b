// The model choice's foil and the integrability check between it and a mirror lobe
// (solve/model_choice.h, solve/highlight_check.h), on renders with exact ground truth: a
// brightening that follows the normal goes to the foil and leaves the normals where they are; a
// highlight goes to the mirror lobe; and where both models are offered, the one whose normals make
// a surface is kept.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "solve/highlight_check.h"
#include "solve/metrics.h"
#include "solve/model_choice.h"
#include "solve/normals.h"
#include "synthetic_spheres.h"

namespace iphong::solve {
namespace {

using test_data::MakeSphereData;
using test_data::Plastic;
using test_data::Synthetic;

// A sphere whose brightening sits on the normal, (N·L)^8 over a Lambertian term.
Synthetic FoilSphere() {
  reflectance::Material m;
  m.kd = Vec3d(0.5, 0.45, 0.4);
  m.ks = Vec3d(0.35, 0.35, 0.35);
  m.shininess = 8;
  return MakeSphereData(m, 24, 0.002, Vec3d::Zero(), 96, false, reflectance::Lobe::kNormalCentred);
}

double MeanError(const NormalResult& r, const Synthetic& s) {
  return CompareNormals(r.normals, s.out.normal_cam, s.out.mask).mean_deg;
}

TEST(HighlightCheck, TheFoilIsOfferedInTheOpenChoiceAndWhenAskedFor) {
  const auto count = [](const std::vector<ModelCandidate>& family, reflectance::Lobe lobe) {
    return std::count_if(family.begin(), family.end(),
                         [&](const ModelCandidate& m) { return m.lobe == lobe; });
  };
  const reflectance::Lobe foil = reflectance::Lobe::kNormalCentred;
  EXPECT_EQ(count(ModelFamily(std::nullopt), foil), 6);
  EXPECT_EQ(count(ModelFamily(foil), foil), 6);
  EXPECT_EQ(ModelFamily(foil).size(), 6u);
  EXPECT_EQ(count(ModelFamily(reflectance::Lobe::kPhong), foil), 0);
  // Its widths are Phong's, about the normal: half widths 30 degrees down to about 4.
  EXPECT_NEAR(LobeHalfWidthDeg(foil, MinimumShininess(foil)), kMaxLobeHalfWidthDeg, 1e-9);
  EXPECT_EQ(MinimumShininess(foil), MinimumShininess(reflectance::Lobe::kPhong));
}

// A matte sphere: no mirror lobe predicts better than Lambert, so the foil is not scored at all
// (the choice costs what it did without it) and Lambert is chosen; on a glossy one a mirror lobe
// does and the foil's grid is scored; asked for alone, the foil is scored and chosen.
TEST(HighlightCheck, TheFoilIsScoredWhereAMirrorLobeBeatsLambertOrWhenAskedFor) {
  const auto scores_foil = [](const ModelChoice& c) {
    return std::any_of(c.scored.begin(), c.scored.end(), [](const ModelCandidate& m) {
      return m.lobe == reflectance::Lobe::kNormalCentred;
    });
  };
  reflectance::Material matte;
  matte.kd = Vec3d(0.6, 0.5, 0.4);
  const Synthetic m = MakeSphereData(matte, 12, 0.01);
  const ModelChoice choice = ChooseModel(m.data, ModelFamily(std::nullopt), ModelChoiceSettings{});
  EXPECT_EQ(choice.chosen.lobe, reflectance::Lobe::kLambert);
  EXPECT_FALSE(scores_foil(choice));
  const Synthetic g = MakeSphereData(Plastic(), 12, 0.01);
  EXPECT_TRUE(scores_foil(ChooseModel(g.data, ModelFamily(std::nullopt), ModelChoiceSettings{})));
  const ModelChoice alone =
      ChooseModel(m.data, ModelFamily(reflectance::Lobe::kNormalCentred), ModelChoiceSettings{});
  EXPECT_EQ(alone.chosen.lobe, reflectance::Lobe::kNormalCentred);
  EXPECT_FALSE(alone.highlight);
}

TEST(HighlightCheck, ABrighteningThatFollowsTheNormalGoesToTheFoil) {
  const Synthetic s = FoilSphere();
  const NormalResult r = EstimateNormals(s.data, NormalOptions{});
  EXPECT_EQ(r.model, reflectance::Lobe::kNormalCentred) << r.model_choice.note;
  const double error = MeanError(r, s);
  RecordProperty("mean_error_deg", std::to_string(error));
  EXPECT_LT(error, 0.5);
  // Without the foil a mirror lobe takes the brightening by tilting the normals.
  NormalOptions mirror;
  mirror.choose_model = false;
  mirror.model = reflectance::Lobe::kPhong;
  const double bent = MeanError(EstimateNormals(s.data, mirror), s);
  std::printf("foil %.3f deg, Phong alone %.3f deg\n", error, bent);
  EXPECT_GT(bent, 3 * error);
}

TEST(HighlightCheck, ARealHighlightKeepsItsMirrorLobe) {
  const Synthetic s = MakeSphereData(Plastic(), 24, 0.002);
  const NormalResult r = EstimateNormals(s.data, NormalOptions{});
  EXPECT_EQ(r.model, reflectance::Lobe::kPhong) << r.model_choice.note;
  EXPECT_LT(MeanError(r, s), 0.5);
}

// The check itself, each render offered the right model and the wrong one in both roles.
TEST(HighlightCheck, KeepsTheModelWhoseNormalsMakeASurface) {
  ModelCandidate foil, phong;
  foil.lobe = reflectance::Lobe::kNormalCentred;
  foil.shininess = 8;
  phong.lobe = reflectance::Lobe::kPhong;
  phong.shininess = 20;
  struct Case {
    Synthetic s;
    bool highlight_true;
  };
  for (const Case& c :
       {Case{FoilSphere(), false}, Case{MakeSphereData(Plastic(), 24, 0.002), true}}) {
    NormalOptions o;
    o.choose_model = false;
    o.weigh_by_shading = false;
    NormalPlan plan = PlanNormals(c.s.data, o);
    plan.Use(foil);
    plan.model_choice.highlight = phong;
    const HighlightCheck check = CheckHighlight(c.s.data, plan);
    std::printf("%s render: foil %.3f deg, highlight %.3f deg from their surfaces, %zu pixels\n",
                c.highlight_true ? "Phong" : "foil", check.foil_deg, check.highlight_deg,
                check.pixels);
    EXPECT_TRUE(check.asked);
    EXPECT_EQ(check.highlight_kept, c.highlight_true);
    EXPECT_EQ(plan.options.model, c.highlight_true ? phong.lobe : foil.lobe);
    EXPECT_EQ(plan.model_choice.chosen.lobe, plan.options.model);
    EXPECT_NE(
        plan.model_choice.note.find(c.highlight_true ? "the highlight kept" : "the foil kept"),
        std::string::npos)
        << plan.model_choice.note;
    // Every pixel of the 96 × 96 render is on the grid (at most 128 a side).
    EXPECT_EQ(check.step, 1);
    EXPECT_GT(check.pixels, 5000u);
  }
}

TEST(HighlightCheck, NotAskedWithoutAHighlight) {
  const Synthetic s = MakeSphereData(Plastic(), 12, 0.0);
  NormalOptions o;
  NormalPlan plan = PlanNormals(s.data, o);
  plan.model_choice.highlight.reset();
  const ModelCandidate before = plan.model_choice.chosen;
  EXPECT_FALSE(CheckHighlight(s.data, plan).asked);
  EXPECT_EQ(plan.model_choice.chosen.lobe, before.lobe);
}

}  // namespace
}  // namespace iphong::solve
