// Image files: round trips through PNG (8/16-bit) and EXR, atomic writes, errors naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "io/image_io.h"

namespace iphong::io {
namespace {
namespace fs = std::filesystem;

class ImageIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("iphong-io-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  static ImageF Ramp(int w, int h) {
    ImageF image(w, h, 3);
    for (int row = 0; row < h; ++row)
      for (int col = 0; col < w; ++col)
        for (int c = 0; c < 3; ++c)
          image.at(col, row)[c] = static_cast<float>((col + 2 * row + c) % 97) / 96.0f;
    return image;
  }
  fs::path dir_;
};

TEST_F(ImageIoTest, ExrKeepsFloatValuesExactly) {
  ImageF image = Ramp(13, 7);
  image.at(3, 2)[1] = 7.25f;  // unclamped
  image.at(4, 2)[0] = -0.5f;
  WriteImage(Path("a.exr"), image);
  const ImageF back = ReadImage(Path("a.exr"));
  ASSERT_EQ(back.width, 13);
  ASSERT_EQ(back.height, 7);
  ASSERT_EQ(back.channels, 3);
  EXPECT_EQ(back.pixels, image.pixels);
}

TEST_F(ImageIoTest, Png16LinearRoundTripWithinQuantization) {
  const ImageF image = Ramp(32, 16);
  WriteImage(Path("b.png"), image, {16, Encoding::kLinear});
  const ImageF back = ReadImage(Path("b.png"));
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    EXPECT_NEAR(back.pixels[i], image.pixels[i], 0.5 / 65535 + 1e-7);
  }
}

TEST_F(ImageIoTest, Png8SrgbEncodesAndClamps) {
  ImageF image(2, 1, 1);
  image.pixels = {0.5f, 3.0f};
  WriteImage(Path("c.png"), image, {8, Encoding::kSrgb});
  const ImageF back = ReadImage(Path("c.png"));
  EXPECT_NEAR(back.pixels[0], LinearToSrgb(0.5f), 0.5 / 255 + 1e-6);  // ≈ 0.735
  EXPECT_NEAR(back.pixels[0], 0.7354f, 3e-3);
  EXPECT_EQ(back.pixels[1], 1.0f);
}

TEST_F(ImageIoTest, SrgbCurveRoundTrips) {
  for (float x = 0; x <= 1.0f; x += 0.01f) EXPECT_NEAR(SrgbToLinear(LinearToSrgb(x)), x, 1e-5);
}

TEST_F(ImageIoTest, FailedWriteLeavesNothingBehind) {
  EXPECT_THROW(WriteImage(Path("missing-dir/d.png"), Ramp(4, 4)), std::runtime_error);
  EXPECT_THROW(WriteImage(Path("e.png"), Ramp(4, 4), {12, Encoding::kLinear}), std::logic_error);
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(ImageIoTest, CorruptAndMissingFilesAreNamedInTheError) {
  {
    std::ofstream corrupt(Path("corrupt.png"), std::ios::binary);
    corrupt << "\x89PNG\r\n\x1a\n this is not a png";
  }
  for (const std::string name : {"corrupt.png", "absent.png"}) {
    try {
      ReadImage(Path(name));
      ADD_FAILURE() << "expected an error for " << name;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace iphong::io

namespace iphong::io {
namespace {

TEST(Srgb, TheTableGivesTheCurvesValues) {
  ImageF image(65536 + 256 + 3, 1, 1);
  for (int k = 0; k < 65536; ++k) image.pixels[k] = k / 65535.0f;      // 16-bit codes
  for (int k = 0; k < 256; ++k) image.pixels[65536 + k] = k / 255.0f;  // 8-bit codes
  const float others[3] = {0.123456f, 1.5f, -0.25f};                   // no code at all
  std::copy(others, others + 3, image.pixels.begin() + 65536 + 256);
  const ImageF original = image;
  LinearizeSrgb(image);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    ASSERT_NEAR(image.pixels[i], SrgbToLinear(original.pixels[i]), 1e-7f) << i;
  }
  EXPECT_NEAR(image.pixels[65536 + 128], 0.2158605f, 1e-6f);  // 128/255, IEC 61966-2-1
}

}  // namespace
}  // namespace iphong::io
