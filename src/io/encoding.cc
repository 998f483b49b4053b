// How an image's codes encode light (image_io.h): sRGB's transfer function both ways, and what a
// file states of its encoding (a PNG's sRGB, gAMA or iCCP chunk, an ICC profile's curve, JPEG's
// and Exif's conventions), read from its header without decoding its pixels.
#include <OpenImageIO/imageio.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "io/icc_profile.h"
#include "io/image_internal.h"
#include "io/image_io.h"

namespace iphong::io {

float LinearToSrgb(float linear) {
  const float x = std::clamp(linear, 0.0f, 1.0f);
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

float SrgbToLinear(float encoded) {
  const float x = std::clamp(encoded, 0.0f, 1.0f);
  return x <= 0.04045f ? x / 12.92f : std::pow((x + 0.055f) / 1.055f, 2.4f);
}

double DecodeSrgb(double encoded) { return SrgbToLinear(static_cast<float>(encoded)); }

void LinearizeSrgb(ImageF& image) {
  static const std::vector<float> table = [] {  // built once, read-only afterwards
    std::vector<float> t(65536);
    for (int k = 0; k < 65536; ++k) t[k] = SrgbToLinear(k / 65535.0f);
    return t;
  }();
  for (float& v : image.pixels) {
    const float code = v * 65535.0f;
    const int k = static_cast<int>(code + 0.5f);
    v = (k >= 0 && k <= 65535 && std::abs(code - k) < 1e-3f) ? table[k] : SrgbToLinear(v);
  }
}

namespace {

// An iCCP chunk is read, and its profile inflated, up to 1 MB each (display profiles are a few
// kilobytes; a larger one, a printer's tables, is taken as a display profile unread).
constexpr std::uint32_t kMaxIccChunk = 1u << 20;
constexpr std::size_t kMaxIccProfile = std::size_t{1} << 20;

// The chunks a PNG holds before its first IDAT that concern the encoding. Each chunk is a 4-byte
// big-endian length, a 4-byte type, the data and a CRC. An iCCP chunk's profile, inflated, goes to
// `profile` (OpenImageIO 2.4 does not report a PNG's).
void ReadPngStatement(const std::string& path, StoredEncoding* e,
                      std::vector<unsigned char>* profile) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return;
  struct Close {
    std::FILE* f;
    ~Close() { std::fclose(f); }
  } closer{f};
  unsigned char signature[8];
  if (std::fread(signature, 1, 8, f) != 8) return;
  for (int chunk = 0; chunk < 64; ++chunk) {
    unsigned char head[8];
    if (std::fread(head, 1, 8, f) != 8) return;
    const std::uint32_t length = (std::uint32_t(head[0]) << 24) | (std::uint32_t(head[1]) << 16) |
                                 (std::uint32_t(head[2]) << 8) | head[3];
    const std::string type(reinterpret_cast<const char*>(head + 4), 4);
    if (type == "IDAT" || type == "IEND") return;
    if (type == "iCCP") {
      // name, NUL, compression method 0, then the profile as a zlib stream. A profile whose
      // curve ReadStoredEncoding cannot read is a display profile (sRGB, Adobe RGB, Display P3):
      // all encode with a curve close to sRGB's.
      e->stated = true;
      e->encoding = Encoding::kSrgb;
      e->statement = "ICC profile";
      std::vector<unsigned char> chunk(std::min(length, kMaxIccChunk));
      if (length > kMaxIccChunk || std::fread(chunk.data(), 1, length, f) != length) return;
      const auto nul = std::find(chunk.begin(), chunk.end(), 0);
      if (chunk.end() - nul <= 2) return;
      profile->resize(kMaxIccProfile);
      uLongf size = profile->size();
      if (uncompress(profile->data(), &size, &*(nul + 2), chunk.end() - nul - 2) != Z_OK) size = 0;
      profile->resize(size);
      return;
    }
    if (type == "sRGB") {
      e->stated = true;
      e->encoding = Encoding::kSrgb;
      e->statement = "sRGB chunk";
      return;
    }
    if (type == "gAMA" && length == 4) {
      unsigned char g[4];
      if (std::fread(g, 1, 4, f) != 4) return;
      const double gamma = ((std::uint32_t(g[0]) << 24) | (std::uint32_t(g[1]) << 16) |
                            (std::uint32_t(g[2]) << 8) | g[3]) /
                           1e5;
      e->stated = true;
      // gAMA stores the encoding exponent: 1 is linear, 1/2.2 is what sRGB approximates.
      e->encoding = std::abs(gamma - 1) < 0.05 ? Encoding::kLinear : Encoding::kSrgb;
      char text[32];
      std::snprintf(text, sizeof text, "gAMA %.5g", gamma);
      e->statement = text;
      return;
    }
    if (std::fseek(f, static_cast<long>(length) + 4, SEEK_CUR) != 0) return;
  }
}

}  // namespace

StoredEncoding ReadStoredEncoding(const std::string& path) {
  StoredEncoding e;
  auto in = internal::OpenImageChecked(path, &e.header);
  const OIIO::ImageSpec& spec = in->spec();
  e.format = in->format_name();
  e.bits = spec.get_int_attribute("oiio:BitsPerSample", static_cast<int>(spec.format.size()) * 8);
  std::vector<unsigned char> profile;
  if (const OIIO::ParamValue* p = spec.find_attribute("ICCProfile")) {
    const auto* bytes = static_cast<const unsigned char*>(p->data());
    profile.assign(bytes, bytes + p->type().size());
  }
  in->close();
  if (e.header.is_float) return e;
  if (e.format == "raw") {
    e.stated = true;  // decoded linear above, whatever the camera's Exif says of its JPEGs
    e.encoding = Encoding::kLinear;
    e.statement = "camera raw, developed linear";
    return e;
  }
  if (e.format == "png") ReadPngStatement(path, &e, &profile);
  // The profile's own curve, before any format's convention.
  if (const IccTransfer icc = ReadIccTransfer(profile.data(), profile.size()); icc.found) {
    e.stated = true;
    e.encoding = icc.linear ? Encoding::kLinear : Encoding::kSrgb;
    e.statement = icc.statement;
    return e;
  }
  if (e.format == "jpeg") {
    e.stated = true;
    e.encoding = Encoding::kSrgb;
    e.statement = "JPEG";
  }
  if (!e.stated && spec.get_int_attribute("Exif:ColorSpace", 0) == 1) {
    e.stated = true;
    e.encoding = Encoding::kSrgb;
    e.statement = "Exif ColorSpace sRGB";
  }
  return e;
}

}  // namespace iphong::io
