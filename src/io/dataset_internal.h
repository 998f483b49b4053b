// Pieces of the dataset reader shared by io/dataset.cc and io/capture_bands.cc (not public).
#pragma once

#include <string>

#include "core/image_ops.h"
#include "io/dataset.h"

namespace iphong::io::internal {

// A dataset found and checked, its images not read: the files, the mask (at the working size),
// the ground truth when asked, and how each image is brought to the working size.
struct Prepared {
  Dataset d;
  PixelRect crop;  // width 0 = none
  Mask file_mask;  // the mask at the files' resolution, cropped: where pixels are counted
  bool srgb = false;
  std::size_t counted_pixels = 0;  // file_mask.count(): every image's counts are out of it
};

Prepared Prepare(const std::string& directory, const DatasetLoadOptions& options);

// Gray (one channel) to RGB by repetition; RGBA loses A.
ImageF ToRgb(ImageF image);

// Decoded rows of a capture file (full width) brought to the working size, as every reader of
// captures does: to RGB; rows [skip, skip + count) and the crop's columns kept; the clipped and
// black pixels counted into `counts` (when given) inside the file mask, whose row `file_y0` the
// first kept row is (cropped frame); sRGB linearized; downscaled. A value that is not finite
// inside the file mask throws std::runtime_error naming `path`, the count and the first pixel.
ImageF WorkingRows(const Prepared& p, ImageF rows, int skip, int count, int file_y0, int downscale,
                   ImageCounts* counts, const std::string& path);

}  // namespace iphong::io::internal
