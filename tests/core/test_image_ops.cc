// Crop and area downscaling: exact values on small images, and the rules at the mask's edge.
#include <gtest/gtest.h>

#include "core/image_ops.h"

namespace iphong {
namespace {

ImageF Ramp(int w, int h, int channels) {
  ImageF image(w, h, channels);
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col)
      for (int c = 0; c < channels; ++c) image.at(col, row)[c] = float(100 * row + col + 1000 * c);
  return image;
}

TEST(ImageOps, CropKeepsTheRectangle) {
  const ImageF image = Ramp(7, 5, 3);
  const ImageF cut = CropImage(image, {2, 1, 4, 3});
  ASSERT_EQ(cut.width, 4);
  ASSERT_EQ(cut.height, 3);
  EXPECT_EQ(cut.at(0, 0)[0], 102);   // (col 2, row 1)
  EXPECT_EQ(cut.at(3, 2)[2], 2305);  // (col 5, row 3), channel 2
  EXPECT_EQ(CheckRect({2, 1, 4, 3}, 7, 5), "");
  EXPECT_NE(CheckRect({4, 1, 4, 3}, 7, 5).find("outside the 7x5 image"), std::string::npos);
  EXPECT_NE(CheckRect({0, 0, 0, 3}, 7, 5), "");
}

TEST(ImageOps, DownscaleAveragesBlocksAndDropsThePartialEdge) {
  const ImageF image = Ramp(7, 5, 1);
  const ImageF small = DownscaleImage(image, 2);
  ASSERT_EQ(small.width, 3);  // column 6 and row 4 make no whole block
  ASSERT_EQ(small.height, 2);
  // Block (cols 2-3, rows 2-3): (202 + 203 + 302 + 303) / 4.
  EXPECT_FLOAT_EQ(small.at(1, 1)[0], 252.5f);
  int w = 0, h = 0;
  PixelRect crop{1, 1, 6, 4};
  TransformedSize(7, 5, &crop, 2, &w, &h);
  EXPECT_EQ(w, 3);
  EXPECT_EQ(h, 2);
}

TEST(ImageOps, ADownscaledMaskKeepsOnlyWholeBlocks) {
  Mask mask(4, 2, true);
  mask.inside[3] = 0;  // (col 3, row 0): the right block is no longer whole
  const Mask small = DownscaleMask(mask, 2);
  ASSERT_EQ(small.width, 2);
  EXPECT_TRUE(small.at(0, 0));
  EXPECT_FALSE(small.at(1, 0));
  const Mask cut = CropMask(mask, {2, 0, 2, 2});
  EXPECT_FALSE(cut.at(1, 0));
  EXPECT_TRUE(cut.at(0, 1));
}

TEST(ImageOps, DownscaledNormalsAreUnitInsideAndZeroAtTheEdge) {
  ImageF normals(4, 2, 3);
  const float a[3] = {0.6f, 0, 0.8f}, b[3] = {-0.6f, 0, 0.8f};
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 2; ++row)
      std::copy(col % 2 ? b : a, (col % 2 ? b : a) + 3, normals.at(col, row));
  std::fill(normals.at(3, 1), normals.at(3, 1) + 3, 0.0f);  // outside the object
  const ImageF small = DownscaleNormals(normals, 2);
  EXPECT_FLOAT_EQ(small.at(0, 0)[0], 0);  // mean of the two tilts: straight up
  EXPECT_FLOAT_EQ(small.at(0, 0)[2], 1);
  EXPECT_EQ(small.at(1, 0)[2], 0);  // a block reaching outside the object
}

}  // namespace
}  // namespace iphong
