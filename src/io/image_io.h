// Reading and writing images with OpenImageIO. The only place pixels touch the disk.
//
// In memory images are linear float (core/types.h). 8/16-bit files are written clamped to [0, 1],
// optionally sRGB-encoded; float files (EXR, float TIFF) keep the values as they are.
#pragma once

#include <string>

#include "core/types.h"

namespace iphong::io {

enum class Encoding {
  kLinear,  // values written as they are (scaled to the integer range for 8/16-bit)
  kSrgb,    // sRGB transfer curve applied before quantizing (8/16-bit only)
};

struct WriteOptions {
  // Bits per channel for integer formats: 8 or 16. Ignored by float formats (.exr, .hdr).
  int bits = 8;
  Encoding encoding = Encoding::kSrgb;
};

// Writes atomically: a temporary file beside `path` is renamed over it only once complete, so a
// failure never leaves a half-written image. Throws std::runtime_error naming the file.
void WriteImage(const std::string& path, const ImageF& image, const WriteOptions& options = {});

// Reads any format OpenImageIO knows into linear float, integer formats scaled to [0, 1]
// (no transfer curve is undone). Throws std::runtime_error naming the file.
ImageF ReadImage(const std::string& path);

// The sRGB transfer curve and its inverse, on [0, 1].
float LinearToSrgb(float linear);
float SrgbToLinear(float encoded);

}  // namespace iphong::io
