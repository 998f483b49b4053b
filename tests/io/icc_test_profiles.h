// ICC profiles of one tone curve, built byte by byte for the tests (ICC.1:2010): the profile
// reader's unit tests and the fuzz driver's seeds.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace iphong::io::icc_test {

inline std::string Be32(std::uint32_t v) {
  return std::string{char(v >> 24), char((v >> 16) & 0xff), char((v >> 8) & 0xff), char(v & 0xff)};
}

// A profile of one tag, `trc` (a 'curv' or 'para' element) under `name` (rTRC or kTRC), with the
// header as libpng checks it: v4.3, a display's RGB (or grey) profile to XYZ under D50.
inline std::string IccProfile(const std::string& trc, const std::string& name = "rTRC") {
  std::string header(128, '\0');
  const std::string element = trc + std::string((4 - trc.size() % 4) % 4, '\0');
  header.replace(0, 4, Be32(128 + 4 + 12 + static_cast<std::uint32_t>(element.size())));
  header.replace(8, 4, Be32(0x04300000));
  header.replace(12, 12, std::string("mntr") + (name == "kTRC" ? "GRAY" : "RGB ") + "XYZ ");
  header.replace(36, 4, "acsp");
  header.replace(68, 12, Be32(0xF6D6) + Be32(0x10000) + Be32(0xD32D));
  return header + Be32(1) + name + Be32(144) + Be32(static_cast<std::uint32_t>(trc.size())) +
         element;
}

// A 'curv' element: no entries (identity), one (a u8Fixed8 gamma) or a table.
inline std::string Curv(const std::vector<std::uint16_t>& entries) {
  std::string out =
      std::string("curv") + Be32(0) + Be32(static_cast<std::uint32_t>(entries.size()));
  for (std::uint16_t v : entries) out += {char(v >> 8), char(v & 0xff)};
  return out;
}

// A 'para' element of function type 0–4 and its s15Fixed16 parameters.
inline std::string Para(int function, const std::vector<double>& parameters) {
  std::string out = std::string("para") + Be32(0) + std::string{char(0), char(function), 0, 0};
  for (double v : parameters) {
    out += Be32(static_cast<std::uint32_t>(static_cast<std::int32_t>(std::lround(v * 65536))));
  }
  return out;
}

}  // namespace iphong::io::icc_test
