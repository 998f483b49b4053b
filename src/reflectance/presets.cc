#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "reflectance/material.h"

namespace iphong::reflectance {
namespace {

Material Grey(double ka, double kd, double ks, double shininess) {
  Material m;
  m.ka = Vec3d::Constant(ka);
  m.kd = Vec3d::Constant(kd);
  m.ks = Vec3d::Constant(ks);
  m.shininess = shininess;
  return m;
}

Material Rgb3(const Vec3d& ka, const Vec3d& kd, const Vec3d& ks, double shininess) {
  Material m;
  m.ka = ka;
  m.kd = kd;
  m.ks = ks;
  m.shininess = shininess;
  return m;
}

std::vector<MaterialPreset> MakePresets() {
  const std::string phong = "seed 000: Phong's material table";
  const std::string tutorial = "seed 004: tutorial PhongMaterials";
  const std::string midpoint = "shininess is the midpoint of the published range ";
  return {
      {"matte", Grey(0.3, 0.7, 0.0, 1.0), phong,
       "no specular term (ks = 0); the table gives no shininess, 1 is a placeholder"},
      {"plastic", Grey(0.2, 0.6, 0.2, 20.0), phong, midpoint + "10-30"},
      {"polished-wood", Grey(0.1, 0.6, 0.3, 40.0), phong, midpoint + "30-50"},
      {"rough-metal", Grey(0.1, 0.3, 0.6, 75.0), phong, midpoint + "50-100"},
      // Seed 004 also has a "chrome"; Phong's keeps his name as a prefix.
      {"phong-chrome", Grey(0.1, 0.2, 0.7, 150.0), phong, midpoint + "100-200"},
      {"brass", Rgb3({0.33, 0.22, 0.03}, {0.78, 0.57, 0.11}, {0.99, 0.91, 0.81}, 27.8), tutorial,
       ""},
      {"gold", Rgb3({0.25, 0.20, 0.07}, {0.75, 0.61, 0.23}, {0.63, 0.56, 0.37}, 51.2), tutorial,
       ""},
      {"silver", Rgb3({0.19, 0.19, 0.19}, {0.51, 0.51, 0.51}, {0.51, 0.51, 0.51}, 51.2), tutorial,
       ""},
      {"chrome", Rgb3({0.25, 0.25, 0.25}, {0.40, 0.40, 0.40}, {0.77, 0.77, 0.77}, 76.8), tutorial,
       ""},
      {"rubber", Rgb3({0.02, 0.02, 0.02}, {0.01, 0.01, 0.01}, {0.40, 0.40, 0.40}, 10.0), tutorial,
       "black rubber"},
      {"jade", Rgb3({0.14, 0.22, 0.16}, {0.54, 0.89, 0.63}, {0.32, 0.32, 0.32}, 12.8), tutorial,
       ""},
      {"pearl", Rgb3({0.25, 0.21, 0.21}, {1.00, 0.83, 0.83}, {0.30, 0.30, 0.30}, 11.3), tutorial,
       ""},
      {"red-plastic", Rgb3({0.0, 0.0, 0.0}, {0.5, 0.0, 0.0}, {0.7, 0.6, 0.6}, 32.0), tutorial,
       "plastic_red in the tutorial"},
  };
}

std::string NormalizeName(std::string name) {
  for (char& c : name) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (c == '_' || c == ' ') c = '-';
  }
  return name;
}

}  // namespace

const std::vector<MaterialPreset>& MaterialPresets() {
  static const std::vector<MaterialPreset> presets = MakePresets();
  return presets;
}

const MaterialPreset& FindMaterialPreset(const std::string& name) {
  const std::string key = NormalizeName(name);
  const auto& presets = MaterialPresets();
  auto it = std::find_if(presets.begin(), presets.end(),
                         [&](const MaterialPreset& p) { return p.name == key; });
  if (it != presets.end()) return *it;
  std::string known;
  for (const auto& p : presets) known += (known.empty() ? "" : ", ") + p.name;
  throw std::invalid_argument("unknown material preset '" + name + "' (known: " + known + ")");
}

}  // namespace iphong::reflectance
