// Presets carry the published values; validation turns bad coefficients and lights into messages.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "reflectance/lighting.h"
#include "reflectance/material.h"

namespace iphong::reflectance {
namespace {

void ExpectMaterial(const std::string& name, const Vec3d& ka, const Vec3d& kd, const Vec3d& ks,
                    double shininess) {
  const Material& m = FindMaterialPreset(name).material;
  EXPECT_EQ(m.ka, ka) << name;
  EXPECT_EQ(m.kd, kd) << name;
  EXPECT_EQ(m.ks, ks) << name;
  EXPECT_EQ(m.shininess, shininess) << name;
}

TEST(MaterialPresets, TutorialTableSeed004) {
  ExpectMaterial("brass", {0.33, 0.22, 0.03}, {0.78, 0.57, 0.11}, {0.99, 0.91, 0.81}, 27.8);
  ExpectMaterial("gold", {0.25, 0.20, 0.07}, {0.75, 0.61, 0.23}, {0.63, 0.56, 0.37}, 51.2);
  ExpectMaterial("silver", {0.19, 0.19, 0.19}, {0.51, 0.51, 0.51}, {0.51, 0.51, 0.51}, 51.2);
  ExpectMaterial("chrome", {0.25, 0.25, 0.25}, {0.40, 0.40, 0.40}, {0.77, 0.77, 0.77}, 76.8);
  ExpectMaterial("rubber", {0.02, 0.02, 0.02}, {0.01, 0.01, 0.01}, {0.40, 0.40, 0.40}, 10.0);
  ExpectMaterial("jade", {0.14, 0.22, 0.16}, {0.54, 0.89, 0.63}, {0.32, 0.32, 0.32}, 12.8);
  ExpectMaterial("pearl", {0.25, 0.21, 0.21}, {1.00, 0.83, 0.83}, {0.30, 0.30, 0.30}, 11.3);
  ExpectMaterial("red-plastic", {0, 0, 0}, {0.5, 0, 0}, {0.7, 0.6, 0.6}, 32.0);
}

TEST(MaterialPresets, PhongTableSeed000WithRangeMidpoints) {
  const Vec3d one = Vec3d::Ones();
  ExpectMaterial("matte", 0.3 * one, 0.7 * one, 0.0 * one, 1.0);
  ExpectMaterial("plastic", 0.2 * one, 0.6 * one, 0.2 * one, 20.0);
  ExpectMaterial("polished-wood", 0.1 * one, 0.6 * one, 0.3 * one, 40.0);
  ExpectMaterial("rough-metal", 0.1 * one, 0.3 * one, 0.6 * one, 75.0);
  ExpectMaterial("phong-chrome", 0.1 * one, 0.2 * one, 0.7 * one, 150.0);
  // Phong's table keeps ka + kd + ks = 1 (seed 000: "to conserve energy").
  for (const auto& p : MaterialPresets()) {
    if (p.source.find("seed 000") == std::string::npos) continue;
    EXPECT_NEAR(p.material.ka[0] + p.material.kd[0] + p.material.ks[0], 1.0, 1e-12) << p.name;
  }
}

TEST(MaterialPresets, AllThirteenValidAndNamedUniquely) {
  const auto& presets = MaterialPresets();
  EXPECT_EQ(presets.size(), 13u);
  for (std::size_t i = 0; i < presets.size(); ++i) {
    EXPECT_EQ(ValidateMaterial(presets[i].material), "") << presets[i].name;
    for (std::size_t j = i + 1; j < presets.size(); ++j)
      EXPECT_NE(presets[i].name, presets[j].name);
  }
}

TEST(MaterialPresets, LookupIsForgivingAboutCaseAndSeparators) {
  EXPECT_EQ(&FindMaterialPreset("Polished_Wood"), &FindMaterialPreset("polished-wood"));
  EXPECT_EQ(&FindMaterialPreset("RED PLASTIC"), &FindMaterialPreset("red-plastic"));
  try {
    FindMaterialPreset("unobtainium");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unobtainium"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("jade"), std::string::npos);  // lists known names
  }
}

TEST(MaterialValidation, RejectsNegativeAndNonFiniteCoefficients) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Material m = FindMaterialPreset("jade").material;
  EXPECT_EQ(ValidateMaterial(m), "");
  Material bad = m;
  bad.ks[1] = -0.1;
  EXPECT_NE(ValidateMaterial(bad).find("ks"), std::string::npos);
  bad = m;
  bad.kd[2] = nan;
  EXPECT_NE(ValidateMaterial(bad).find("kd"), std::string::npos);
  bad = m;
  bad.shininess = -1;
  EXPECT_NE(ValidateMaterial(bad).find("shininess"), std::string::npos);
  bad.shininess = std::numeric_limits<double>::infinity();
  EXPECT_THROW(CheckMaterial(bad), std::invalid_argument);
}

TEST(LightValidation, DirectionIsNormalizedAndZeroOrNanRejected) {
  const Light light = Light::Directional(Vec3d(0, 0, 5), Vec3d::Ones());
  EXPECT_EQ(light.direction_cam, Vec3d(0, 0, 1));
  EXPECT_THROW(Light::Directional(Vec3d::Zero(), Vec3d::Ones()), std::invalid_argument);
  // Huge and tiny components still have a direction.
  EXPECT_NEAR(Light::Directional(Vec3d(1e308, 1e308, 1e308), Vec3d::Ones()).direction_cam.z(),
              1 / std::sqrt(3.0), 1e-15);
  EXPECT_NEAR(Light::Directional(Vec3d(0, 3e-300, 4e-300), Vec3d::Ones()).direction_cam.z(), 0.8,
              1e-15);
  EXPECT_THROW(Light::Directional(Vec3d(std::nan(""), 0, 1), Vec3d::Ones()), std::invalid_argument);
  EXPECT_THROW(Light::Directional(Vec3d(0, 0, 1), Vec3d(1, -1, 1)), std::invalid_argument);
  EXPECT_THROW(Light::Point(Vec3d(0, std::nan(""), 0), Vec3d::Ones(), true), std::invalid_argument);
}

TEST(LightValidation, LightingNamesTheBadLight) {
  Lighting lighting;
  lighting.lights = {Light::Directional(Vec3d(0, 0, 1), Vec3d::Ones()),
                     Light::Directional(Vec3d(0, 1, 1), Vec3d::Ones())};
  EXPECT_EQ(lighting.Validate(), "");
  lighting.lights[1].diffuse_intensity[0] = -2;
  EXPECT_EQ(lighting.Validate().rfind("light 1:", 0), 0u) << lighting.Validate();
  lighting.lights[1].diffuse_intensity[0] = 1;
  lighting.ambient = Vec3d(0, -1, 0);
  EXPECT_NE(lighting.Validate().find("ambient"), std::string::npos);
}

TEST(ModelNames, ParseAndPrintRoundTrip) {
  for (Lobe lobe : {Lobe::kPhong, Lobe::kBlinnPhong, Lobe::kLambert, Lobe::kNormalCentred}) {
    EXPECT_EQ(ParseLobe(LobeName(lobe)), lobe);
  }
  EXPECT_THROW(ParseLobe("cook-torrance"), std::invalid_argument);
}

}  // namespace
}  // namespace iphong::reflectance

namespace iphong::reflectance {
namespace {

// SPEC.md's LED: E(X) = Φ·(a·(X − S)/|X − S|)^μ/|X − S|², the same factor on the specular
// intensity, nothing behind the LED, and μ = 0 an isotropic point light.
TEST(LedLight, IrradianceIsTheClosedForm) {
  const Vec3d s(0, 0, 0), axis = Vec3d(0, 0.6, -0.8);
  const Vec3d x(30, 10, -400);
  const double d2 = (x - s).squaredNorm();
  const double cosine = axis.dot((x - s).normalized());
  for (double mu : {0.0, 1.0, 2.5}) {
    const Light led = Light::Led(s, Vec3d(1e5, 2e5, 3e5), axis * 5, mu);
    EXPECT_NEAR(led.axis_cam.norm(), 1, 1e-15);
    Vec3d dir, diffuse, specular;
    ASSERT_TRUE(LightAt<double>(led, x, &dir, &diffuse, &specular));
    EXPECT_NEAR((dir - (s - x).normalized()).norm(), 0, 1e-15);
    for (int c = 0; c < 3; ++c) {
      const double expected = 1e5 * (c + 1) * std::pow(cosine, mu) / d2;
      EXPECT_NEAR(diffuse[c], expected, 1e-12 * expected) << "mu " << mu;
      EXPECT_NEAR(specular[c], expected, 1e-12 * expected) << "mu " << mu;
    }
    // Behind the LED (the axis turned away from the point): no light, but still a direction.
    const Light away = Light::Led(s, Vec3d::Ones(), -axis, mu);
    ASSERT_TRUE(LightAt<double>(away, x, &dir, &diffuse, &specular));
    if (mu > 0) {
      EXPECT_EQ(diffuse, Vec3d::Zero());
    } else {
      EXPECT_NEAR(diffuse[0], 1 / d2, 1e-18);
    }
  }
  EXPECT_THROW(Light::Led(s, Vec3d::Ones(), Vec3d::Zero(), 1), std::invalid_argument);
  EXPECT_THROW(Light::Led(s, Vec3d::Ones(), axis, -1), std::invalid_argument);
  EXPECT_THROW(Light::Led(s, Vec3d::Ones(), axis, std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace iphong::reflectance
