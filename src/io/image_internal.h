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

// The header as displayed under `orientation` (kFileOrientation: the file's own), its
// orientation field still the file's statement. Throws std::logic_error outside 0–8.
ImageHeader Oriented(const ImageHeader& file_header, int orientation);

// The stored pixel shown at displayed (x, y) under `orientation`, for a stored image of
// stored_width × stored_height, as the Exif standard's table defines it (where the stored 0th row
// and 0th column are seen). Written here, not left to ImageBufAlgo::reorient: OpenImageIO up to
// 2.5 swaps codes 5 and 7 (its issue #4661), and bands need the mapping row by row.
inline void StoredPixel(int orientation, int stored_width, int stored_height, int x, int y, int* sx,
                        int* sy) {
  switch (orientation) {
    case 2:
      *sx = stored_width - 1 - x, *sy = y;
      return;
    case 3:
      *sx = stored_width - 1 - x, *sy = stored_height - 1 - y;
      return;
    case 4:
      *sx = x, *sy = stored_height - 1 - y;
      return;
    case 5:
      *sx = y, *sy = x;
      return;
    case 6:
      *sx = y, *sy = stored_height - 1 - x;
      return;
    case 7:
      *sx = stored_width - 1 - y, *sy = stored_height - 1 - x;
      return;
    case 8:
      *sx = stored_width - 1 - y, *sy = x;
      return;
    default:
      *sx = x, *sy = y;
      return;
  }
}

// The stored image as displayed under `orientation` (1–8).
ImageF Reorient(const ImageF& stored, int orientation);

// .exr, .hdr, .pfm: float values stored as they are.
bool IsFloatImagePath(const std::string& path);

}  // namespace iphong::io::internal
