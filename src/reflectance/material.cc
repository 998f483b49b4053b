#include "reflectance/material.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace iphong::reflectance {
namespace {

std::string CheckCoefficient(const char* name, const Vec3d& value) {
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(value[c]) || value[c] < 0) {
      std::ostringstream message;
      message << "material " << name << " must be finite and >= 0 in every channel, got ["
              << value[0] << ", " << value[1] << ", " << value[2] << "]";
      return message.str();
    }
  }
  return "";
}

}  // namespace

std::string ValidateMaterial(const Material& material) {
  for (const auto& [name, value] : {std::pair<const char*, const Vec3d&>{"ka", material.ka},
                                    {"kd", material.kd},
                                    {"ks", material.ks}}) {
    if (std::string message = CheckCoefficient(name, value); !message.empty()) return message;
  }
  if (!std::isfinite(material.shininess) || material.shininess < 0) {
    std::ostringstream message;
    message << "material shininess must be finite and >= 0, got " << material.shininess;
    return message.str();
  }
  return "";
}

void CheckMaterial(const Material& material) {
  if (std::string message = ValidateMaterial(material); !message.empty()) {
    throw std::invalid_argument(message);
  }
}

Lobe ParseLobe(const std::string& name) {
  if (name == "phong") return Lobe::kPhong;
  if (name == "blinn-phong" || name == "blinn_phong" || name == "blinn") return Lobe::kBlinnPhong;
  if (name == "lambert") return Lobe::kLambert;
  if (name == "normal-centred" || name == "normal_centred") return Lobe::kNormalCentred;
  if (name == "oren-nayar" || name == "oren_nayar") return Lobe::kOrenNayar;
  throw std::invalid_argument(
      "unknown reflectance model '" + name +
      "' (expected phong, blinn-phong, lambert, oren-nayar or normal-centred)");
}

std::string LobeName(Lobe lobe) {
  switch (lobe) {
    case Lobe::kPhong:
      return "phong";
    case Lobe::kBlinnPhong:
      return "blinn-phong";
    case Lobe::kLambert:
      return "lambert";
    case Lobe::kNormalCentred:
      return "normal-centred";
    case Lobe::kOrenNayar:
      return "oren-nayar";
  }
  return "phong";
}

}  // namespace iphong::reflectance
