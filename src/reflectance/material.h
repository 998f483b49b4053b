// Materials: Phong coefficients in double precision, their validation and the named presets.
#pragma once

#include <string>
#include <vector>

#include "reflectance/phong.h"

namespace iphong::reflectance {

using Material = MaterialT<double>;

// Empty when the material is valid, else a one-line message: every coefficient finite and
// ≥ 0, shininess finite and ≥ 0. (kd > 1 is allowed: real albedos are relative.)
std::string ValidateMaterial(const Material& material);

// Throws std::invalid_argument with ValidateMaterial's message.
void CheckMaterial(const Material& material);

// A published material: the coefficients plus where they come from.
struct MaterialPreset {
  std::string name;  // lookup key, lower case with dashes
  Material material;
  std::string source;  // which seed table
  std::string note;    // how a published range was turned into one value, if it was
};

// Every preset, in the order of the two tables: Phong's (seed 000) then the tutorial's (seed 004).
const std::vector<MaterialPreset>& MaterialPresets();

// Looks a preset up by name (case-insensitive; '_' and ' ' count as '-'). Throws
// std::invalid_argument listing the known names when there is none.
const MaterialPreset& FindMaterialPreset(const std::string& name);

// Parses "phong", "blinn-phong" or "lambert"; throws std::invalid_argument otherwise.
Lobe ParseLobe(const std::string& name);
std::string LobeName(Lobe lobe);

}  // namespace iphong::reflectance
