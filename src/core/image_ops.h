// Cropping and area downscaling of images, masks and normal maps, so a camera-sized capture can
// be cut to the object and reduced before anything else reads it. All three are cut and reduced
// the same way, so pixel (col, row) of each still describes the same point.
#pragma once

#include <string>

#include "core/types.h"

namespace iphong {

// A rectangle of pixels: columns [x, x + width), rows [y, y + height), row 0 at the top.
struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
};

// "" when `rect` lies inside a width × height image and is not empty, else what is wrong.
std::string CheckRect(const PixelRect& rect, int width, int height);

// The size an image of width × height has after `crop` (when not empty) and `downscale`
// (width / downscale, rounded down: a partial block at the right or bottom edge is dropped).
void TransformedSize(int width, int height, const PixelRect* crop, int downscale, int* out_width,
                     int* out_height);

ImageF CropImage(const ImageF& image, const PixelRect& rect);
Mask CropMask(const Mask& mask, const PixelRect& rect);

// Each output pixel is the mean of a factor × factor block (area averaging: no aliasing, and the
// noise drops by the factor).
ImageF DownscaleImage(const ImageF& image, int factor);

// A block is inside only when all its pixels are: a pixel averaged over object and background
// would mix the background's values into the object's shading.
Mask DownscaleMask(const Mask& mask, int factor);

// Normals averaged over a block and renormalized; zero where the block holds a zero vector
// (outside the object), so the map stays "unit inside, 0 outside".
ImageF DownscaleNormals(const ImageF& normals, int factor);

}  // namespace iphong
