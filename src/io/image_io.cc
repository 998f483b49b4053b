#include "io/image_io.h"

#include "io/staging.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace iphong::io {
namespace fs = std::filesystem;

namespace {

bool IsFloatFormat(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".exr" || ext == ".hdr" || ext == ".pfm";
}

[[noreturn]] void Fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + what);
}

}  // namespace

float LinearToSrgb(float linear) {
  const float x = std::clamp(linear, 0.0f, 1.0f);
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

float SrgbToLinear(float encoded) {
  const float x = std::clamp(encoded, 0.0f, 1.0f);
  return x <= 0.04045f ? x / 12.92f : std::pow((x + 0.055f) / 1.055f, 2.4f);
}

void WriteImage(const std::string& path, const ImageF& image, const WriteOptions& options) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() != image.pixel_count() * image.channels) {
    Fail(path, "refusing to write an empty or inconsistent image");
  }
  const fs::path target(path);
  const bool is_float = IsFloatFormat(target);
  if (!is_float && options.bits != 8 && options.bits != 16) {
    Fail(path, "integer images are 8 or 16 bits per channel, got " + std::to_string(options.bits));
  }

  std::vector<float> pixels = image.pixels;
  if (!is_float) {
    for (float& v : pixels) {
      if (!std::isfinite(v)) v = 0.0f;
      v = options.encoding == Encoding::kSrgb ? LinearToSrgb(v) : std::clamp(v, 0.0f, 1.0f);
    }
  }

  const OIIO::TypeDesc format =
      is_float ? OIIO::TypeDesc::FLOAT
               : (options.bits == 16 ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8);
  OIIO::ImageSpec spec(image.width, image.height, image.channels, format);
  spec.attribute("oiio:ColorSpace",
                 is_float || options.encoding == Encoding::kLinear ? "Linear" : "sRGB");
  spec.attribute("Software", "iphong");

  WriteFileAtomically(path, [&](const std::string& temp) -> std::string {
    auto out = OIIO::ImageOutput::create(temp);
    if (!out) return "no image writer for this format: " + OIIO::geterror();
    if (!out->open(temp, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) ||
        !out->close()) {
      return "cannot write: " + out->geterror();
    }
    return "";
  });
}

ImageF ReadImage(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    std::string why = OIIO::geterror();
    if (why.empty()) why = "cannot open";
    Fail(path, why);
  }
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) Fail(path, "empty image");
  ImageF image(spec.width, spec.height, spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
    Fail(path, "cannot decode: " + in->geterror());
  }
  in->close();
  return image;
}

}  // namespace iphong::io
