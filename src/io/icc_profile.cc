#include "io/icc_profile.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>

namespace iphong::io {
namespace {

std::uint32_t U32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
         p[3];
}
std::uint16_t U16(const unsigned char* p) { return std::uint16_t((p[0] << 8) | p[1]); }
double S15Fixed16(const unsigned char* p) { return static_cast<std::int32_t>(U32(p)) / 65536.0; }

// y(x) for the 'curv' or 'para' element of `size` bytes at p; none for another element.
std::optional<double> CurveAt(const unsigned char* p, std::size_t size, double x) {
  if (size < 12) return std::nullopt;
  if (U32(p) == U32(reinterpret_cast<const unsigned char*>("curv"))) {
    const std::uint32_t count = U32(p + 8);
    if (count > (size - 12) / 2) return std::nullopt;
    if (count == 0) return x;
    if (count == 1) return std::pow(x, U16(p + 12) / 256.0);  // a u8Fixed8Number gamma
    const double at = x * (count - 1);
    const std::uint32_t i = std::min<std::uint32_t>(static_cast<std::uint32_t>(at), count - 2);
    const double f = at - i;
    return ((1 - f) * U16(p + 12 + 2 * i) + f * U16(p + 14 + 2 * i)) / 65535.0;
  }
  if (U32(p) != U32(reinterpret_cast<const unsigned char*>("para"))) return std::nullopt;
  static constexpr int kParameters[] = {1, 3, 4, 5, 7};
  const int function = U16(p + 8);
  if (function > 4 || size < 12 + 4 * static_cast<std::size_t>(kParameters[function])) {
    return std::nullopt;
  }
  double v[7] = {1, 1, 0, 0, 0, 0, 0};  // g a b c d e f
  for (int i = 0; i < kParameters[function]; ++i) v[i] = S15Fixed16(p + 12 + 4 * i);
  const double g = v[0], a = v[1], b = v[2], c = v[3], d = v[4], e = v[5], f = v[6];
  const auto power = [&](double t) { return t > 0 ? std::pow(t, g) : 0.0; };
  switch (function) {
    case 0:
      return power(x);
    case 1:
      return x >= -b / a ? power(a * x + b) : 0.0;
    case 2:
      return (x >= -b / a ? power(a * x + b) : 0.0) + c;
    case 3:
      return x >= d ? power(a * x + b) : c * x;
    default:
      return x >= d ? power(a * x + b) + e : c * x + f;
  }
}

}  // namespace

IccTransfer ReadIccTransfer(const unsigned char* profile, std::size_t size) {
  IccTransfer out;
  if (profile == nullptr || size < 132 ||
      U32(profile + 36) != U32(reinterpret_cast<const unsigned char*>("acsp"))) {
    return out;
  }
  const std::uint32_t tags = U32(profile + 128);
  if (tags > (size - 132) / 12) return out;
  // The red curve (rTRC) if the profile lists one inside it, else the grey one (kTRC).
  const unsigned char* element = nullptr;
  std::uint32_t length = 0;
  for (const char* wanted : {"kTRC", "rTRC"}) {
    for (std::uint32_t t = 0; t < tags; ++t) {
      const unsigned char* entry = profile + 132 + 12 * t;
      const std::uint32_t offset = U32(entry + 4), bytes = U32(entry + 8);
      if (U32(entry) == U32(reinterpret_cast<const unsigned char*>(wanted)) && offset <= size &&
          bytes <= size - offset) {
        element = profile + offset, length = bytes;
      }
    }
  }
  if (element == nullptr) return out;
  const std::optional<double> low = CurveAt(element, length, 0.2),
                              mid = CurveAt(element, length, 0.5);
  if (!low || !mid || !std::isfinite(*low) || !std::isfinite(*mid) || !(*mid > 0)) return out;
  out.gamma = std::log(*mid) / std::log(0.5);
  if (std::abs(*low - 0.2) <= 0.01 && std::abs(*mid - 0.5) <= 0.01) {
    out.found = out.linear = true;
    out.statement = "ICC profile, linear";
  } else if (out.gamma >= 1.6 && out.gamma <= 3) {
    out.found = true;
    char text[48];
    std::snprintf(text, sizeof text, "ICC profile, gamma %.1f", out.gamma);
    out.statement = text;
  }
  return out;
}

}  // namespace iphong::io
