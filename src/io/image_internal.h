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

// Where a file's pixel data lie in the picture it shows. OpenEXR keeps a data window within a
// display window; viewers show the display window, black where there are no data, and so does
// iphong: the images of a capture are registered by their display windows (a renderer's EXRs
// cropped to what each light lit are still one picture size). Other formats are their data: a
// TIFF's XPosition (a scanner's offset on its bed) is not a black border viewers show.
struct DataPlacement {
  int display_width = 0, display_height = 0;
  int x = 0, y = 0;   // the data window's first pixel in the display window (negative: overscan)
  bool whole = true;  // the data window is the display window: nothing to place
};
DataPlacement PlacementOf(OIIO::ImageInput& in);

// Copies `rows` rows of the data window from data row `data_y0` on (spec.width × rows pixels of
// `channels` floats at `data`) into the display rows they cover of `band`, whose first row is
// display row `band_y0`; what falls outside the display window is dropped.
void PlaceRows(const float* data, int data_width, int data_y0, int rows, int channels,
               const DataPlacement& place, int band_y0, ImageF& band);

// Which channels of a file are its picture. An EXR of several layers (Blender's multilayer
// output: "ViewLayer.AO.R", …, "ViewLayer.Combined.R", …) lists its passes in name order, so its
// first three channels may be any pass; the picture is the layer with R, G and B: the file's
// unnamed layer, else its only one, else the one named Combined, beauty, rgba or color (its last
// part, any case). Sets `first`, `count` (3, or 4 with its A) and `layer`; files of one layer, and
// layers without R, G and B, keep every channel from the first. Throws std::runtime_error naming
// the layers when several colour layers leave the picture unclear.
void ColourLayer(const std::string& path, const OIIO::ImageSpec& spec, int* first, int* count,
                 std::string* layer);

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
