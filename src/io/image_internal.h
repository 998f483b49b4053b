// Pieces of io/image_io.cc shared with io/image_rows.cc (not public).
#pragma once

#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>

#include "io/image_io.h"

namespace iphong::io::internal {

// Opens an image and checks its header (a 2D image, plausible for the file's size). Throws
// std::runtime_error naming the file.
std::unique_ptr<OIIO::ImageInput> OpenImageChecked(const std::string& path, ImageHeader* header);

// .exr, .hdr, .pfm: float values stored as they are.
bool IsFloatImagePath(const std::string& path);

}  // namespace iphong::io::internal
