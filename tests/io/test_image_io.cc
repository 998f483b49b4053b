// Image files: round trips through PNG (8/16-bit) and EXR, atomic writes, errors naming the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <vector>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include "icc_test_profiles.h"
#include "io/icc_profile.h"
#include "io/image_io.h"
#include "io/image_rows.h"

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

// A PNG's alpha is unassociated: its colour is stored as the camera gave it, whatever the alpha.
// OpenImageIO premultiplies colour by alpha unless asked not to, which would darken a photo
// wherever it is partly transparent (a cut-out's soft edge, an export that marks shadows) and
// differently in each image whose alpha differs. Read as stored, the colour is the file's.
TEST_F(ImageIoTest, PngColourIsReadAsStoredWhateverItsAlpha) {
  const int w = 6, h = 2;
  std::vector<std::uint16_t> stored(static_cast<std::size_t>(w) * h * 4);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      std::uint16_t* v = stored.data() + 4 * (row * w + col);
      v[0] = 51200, v[1] = 25600, v[2] = 12800;
      v[3] = col < 2 ? 65535 : col < 5 ? 32768 : 0;  // opaque, half, transparent
    }
  }
  OIIO::ImageSpec spec(w, h, 4, OIIO::TypeDesc::UINT16);
  spec.alpha_channel = 3;
  spec.attribute("oiio:UnassociatedAlpha", 1);  // the values above are written as they are
  auto out = OIIO::ImageOutput::create(Path("rgba.png"));
  ASSERT_TRUE(out && out->open(Path("rgba.png"), spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT16, stored.data()));
  ASSERT_TRUE(out->close());

  const ImageF image = ReadImage(Path("rgba.png"));
  ASSERT_EQ(image.channels, 4);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const float* v = image.at(col, row);
      for (int c = 0; c < 4; ++c) {
        EXPECT_EQ(v[c], stored[4 * (row * w + col) + c] / 65535.0f) << col << " " << c;
      }
    }
  }
  // And iphong writes a fourth channel as given: the same values come back.
  WriteImage(Path("again.png"), image, {16, Encoding::kLinear});
  const ImageF again = ReadImage(Path("again.png"));
  ASSERT_EQ(again.pixels.size(), image.pixels.size());
  for (std::size_t i = 0; i < image.pixels.size(); ++i) EXPECT_EQ(again.pixels[i], image.pixels[i]);
}

// A mask is nonzero colour; a cut-out's alpha, where it varies, marks the object instead (its
// transparent background may keep any colour: white here, the photo in practice); a JPEG's
// compression leaves faint values around the object, so it is read above half its largest value.
TEST_F(ImageIoTest, MasksAreReadAsTheirMakersMeantThem) {
  const auto inside = [](int col, int row) { return col < 3 && row > 0; };
  std::size_t object = 0;
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 6; ++col) object += inside(col, row);
  std::string how = "unset";
  ImageF rgba(6, 4, 4, 1.0f);  // white everywhere, opaque on the object only
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 6; ++col) rgba.at(col, row)[3] = inside(col, row) ? 1.0f : 0.0f;
  WriteImage(Path("cutout.png"), rgba, {8, Encoding::kData});
  Mask m = ReadMask(Path("cutout.png"), {}, &how);
  EXPECT_EQ(m.count(), object);
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 6; ++col) EXPECT_EQ(m.at(col, row), inside(col, row)) << col << row;
  EXPECT_EQ(how, "its alpha channel: transparent = background");

  ImageF grey_alpha(6, 4, 2, 1.0f);  // PNG's grey + alpha: channel 1 is alpha, not colour
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 6; ++col) grey_alpha.at(col, row)[1] = inside(col, row) ? 1.0f : 0.0f;
  WriteImage(Path("grey_alpha.png"), grey_alpha, {8, Encoding::kData});
  EXPECT_EQ(ReadMask(Path("grey_alpha.png"), {}, &how).count(), object);
  EXPECT_EQ(how, "its alpha channel: transparent = background");

  // An opaque alpha says nothing: the colour decides, as in any mask.
  ImageF opaque(6, 4, 4, 1.0f);
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 6; ++col)
      for (int c = 0; c < 3; ++c) opaque.at(col, row)[c] = inside(col, row) ? 1.0f : 0.0f;
  WriteImage(Path("opaque.png"), opaque, {8, Encoding::kData});
  m = ReadMask(Path("opaque.png"), {}, &how);
  EXPECT_EQ(m.count(), object);
  EXPECT_EQ(how, "");

  // A disc in JPEG: its nonzero pixels are a ring wider than the disc; above half, the disc.
  ImageF disc(48, 48, 3, 0.0f);
  std::size_t disc_pixels = 0;
  for (int row = 0; row < 48; ++row)
    for (int col = 0; col < 48; ++col)
      if (std::hypot(col - 23.5, row - 23.5) < 15) {
        ++disc_pixels;
        for (int c = 0; c < 3; ++c) disc.at(col, row)[c] = 1.0f;
      }
  WriteImage(Path("disc.jpg"), disc, {8, Encoding::kData});
  const ImageF stored = ReadImage(Path("disc.jpg"));
  std::size_t nonzero = 0;
  for (std::size_t p = 0; p < stored.pixel_count(); ++p) nonzero += stored.pixels[3 * p] > 0;
  ASSERT_GT(nonzero, disc_pixels + 20) << "the JPEG encoder left no ring to test against";
  m = ReadMask(Path("disc.jpg"), {}, &how);
  EXPECT_EQ(m.count(), disc_pixels);
  EXPECT_EQ(how,
            "above half its largest value: lossy compression leaves faint values around the "
            "object");
}

// A linear DNG (LinearRaw, 3 samples, uncompressed): a raw file LibRaw develops, written here
// since no camera's file can ship with the tests. Little-endian TIFF, one IFD.
void WriteLinearDng(const std::string& path, int width, int height,
                    const std::vector<std::uint16_t>& rgb) {
  struct Entry {
    std::uint16_t tag, type;
    std::uint32_t count;
    std::string bytes;  // the value, little-endian
  };
  const auto u16 = [](std::initializer_list<std::uint16_t> v) {
    std::string out;
    for (std::uint16_t x : v) out += {char(x & 0xff), char(x >> 8)};
    return out;
  };
  const auto u32 = [](std::initializer_list<std::int64_t> v) {
    std::string out;
    for (std::int64_t x : v)
      for (int b = 0; b < 4; ++b) out += char((static_cast<std::uint32_t>(x) >> (8 * b)) & 0xff);
    return out;
  };
  const std::uint32_t data_bytes = static_cast<std::uint32_t>(rgb.size() * 2);
  std::vector<Entry> entries = {
      {254, 4, 1, u32({0})},
      {256, 4, 1, u32({width})},
      {257, 4, 1, u32({height})},
      {258, 3, 3, u16({16, 16, 16})},
      {259, 3, 1, u16({1})},
      {262, 3, 1, u16({34892})},  // LinearRaw
      {271, 2, 8, std::string("iphong\0\0", 8)},
      {272, 2, 8, std::string("testcam\0", 8)},
      {273, 4, 1, ""},  // the strip's offset, set below
      {274, 3, 1, u16({1})},
      {277, 3, 1, u16({3})},
      {278, 4, 1, u32({height})},
      {279, 4, 1, u32({data_bytes})},
      {284, 3, 1, u16({1})},
      {50706, 1, 4, std::string("\x01\x04\x00\x00", 4)},  // DNGVersion 1.4
      {50708, 2, 8, std::string("testcam\0", 8)},
      {50717, 4, 1, u32({65535})},                                                  // WhiteLevel
      {50721, 10, 9, u32({1, 1, 0, 1, 0, 1, 0, 1, 1, 1, 0, 1, 0, 1, 0, 1, 1, 1})},  // identity
      {50728, 5, 3, u32({1, 1, 1, 1, 1, 1})},                                       // AsShotNeutral
  };
  // Header, IFD, the values longer than 4 bytes, then the strip.
  std::uint32_t offset = 8 + 2 + 12 * static_cast<std::uint32_t>(entries.size()) + 4;
  std::uint32_t data_offset = offset;
  for (const Entry& e : entries) data_offset += e.bytes.size() > 4 ? e.bytes.size() : 0;
  std::string ifd = u16({static_cast<std::uint16_t>(entries.size())}), blobs;
  for (const Entry& e : entries) {
    std::string value = e.tag == 273 ? u32({data_offset}) : e.bytes;
    ifd += u16({e.tag, e.type}) + u32({e.count});
    if (value.size() > 4) {
      ifd += u32({offset});
      blobs += value;
      offset += static_cast<std::uint32_t>(value.size());
    } else {
      ifd += value + std::string(4 - value.size(), '\0');
    }
  }
  std::ofstream out(path, std::ios::binary);
  out << std::string("II*\0", 4) << u32({8}) << ifd << u32({0}) << blobs;
  for (std::uint16_t v : rgb) out << char(v & 0xff) << char(v >> 8);
  ASSERT_TRUE(out.good());
}

// Camera raw is read as the sensor recorded it: linear, as photometric stereo needs (OpenImageIO's
// default development applies the sRGB curve: 8000 and 32000 of 65535 came out 25177 and 47682).
// The values are checked, not where LibRaw places them: it lays this hand-made DNG out in its own
// way (the halves come back interleaved), which a real camera's file does not show.
TEST_F(ImageIoTest, CameraRawIsDevelopedLinear) {
  const int w = 64, h = 48;  // LibRaw refuses images under 22 pixels a side
  std::vector<std::uint16_t> rgb(static_cast<std::size_t>(w) * h * 3);
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col)
      for (int c = 0; c < 3; ++c)
        rgb[(std::size_t(row) * w + col) * 3 + c] = col < 32 ? 8000 : 32000;
  WriteLinearDng(Path("shot.dng"), w, h, rgb);
  const StoredEncoding e = ReadStoredEncoding(Path("shot.dng"));
  ASSERT_EQ(e.format, "raw") << "LibRaw did not take the test's DNG";
  EXPECT_TRUE(e.stated);
  EXPECT_EQ(e.encoding, Encoding::kLinear);
  EXPECT_EQ(e.statement, "camera raw, developed linear");
  const ImageF image = ReadImage(Path("shot.dng"));
  ASSERT_EQ(image.width, w);
  ASSERT_EQ(image.height, h);
  for (int c = 0; c < 3; ++c) {
    float low = 1, high = 0;
    for (std::size_t p = 0; p < image.pixel_count(); ++p) {
      low = std::min(low, image.pixels[3 * p + c]);
      high = std::max(high, image.pixels[3 * p + c]);
    }
    // A channel's gain is the camera's daylight multiplier (the same for every photo); the ratio
    // of two exposures is the sensor's.
    EXPECT_NEAR(high / low, 4.0, 0.01) << c;  // the sRGB curve: 1.89
  }
}

using icc_test::Curv;
using icc_test::IccProfile;
using icc_test::Para;

IccTransfer Transfer(const std::string& profile) {
  return ReadIccTransfer(reinterpret_cast<const unsigned char*>(profile.data()), profile.size());
}

// The curves raw developers and colour-managed editors embed, read as the ICC spec defines them.
TEST(IccProfile, TheToneCurveSaysLinearOrDisplayEncoded) {
  IccTransfer t = Transfer(IccProfile(Curv({})));  // identity: darktable's linear profiles
  EXPECT_TRUE(t.found && t.linear);
  EXPECT_EQ(t.statement, "ICC profile, linear");
  t = Transfer(IccProfile(Curv({256})));  // gamma 1.0 as u8Fixed8
  EXPECT_TRUE(t.found && t.linear);
  t = Transfer(IccProfile(Curv({563}), "kTRC"));  // 2.2 (563/256 = 2.199), a grey profile
  EXPECT_TRUE(t.found && !t.linear);
  EXPECT_NEAR(t.gamma, 2.199, 1e-3);
  EXPECT_EQ(t.statement, "ICC profile, gamma 2.2");
  t = Transfer(IccProfile(Curv({0, 65535})));  // a two-point table: linear
  EXPECT_TRUE(t.found && t.linear);
  std::vector<std::uint16_t> table(1024);  // the sRGB decoding curve, sampled
  for (std::size_t i = 0; i < table.size(); ++i) {
    const double x = i / 1023.0;
    table[i] = static_cast<std::uint16_t>(
        std::lround(65535 * (x <= 0.04045 ? x / 12.92 : std::pow((x + 0.055) / 1.055, 2.4))));
  }
  t = Transfer(IccProfile(Curv(table)));
  EXPECT_TRUE(t.found && !t.linear);
  EXPECT_NEAR(t.gamma, std::log(std::pow((0.5 + 0.055) / 1.055, 2.4)) / std::log(0.5), 1e-3);
  // sRGB as ICC v4 writes it: parametric type 3.
  t = Transfer(IccProfile(Para(3, {2.4, 1 / 1.055, 0.055 / 1.055, 1 / 12.92, 0.04045})));
  EXPECT_TRUE(t.found && !t.linear);
  EXPECT_NEAR(t.gamma, 2.22, 0.01);
  t = Transfer(IccProfile(Para(0, {1.0})));
  EXPECT_TRUE(t.found && t.linear);
  // What is not understood says nothing: a gamma of 1.2, no curve tag, a truncated profile.
  EXPECT_FALSE(Transfer(IccProfile(Curv({307}))).found);
  EXPECT_FALSE(Transfer(IccProfile(Curv({}), "gTRC")).found);
  const std::string whole = IccProfile(Curv(table));
  EXPECT_FALSE(Transfer(whole.substr(0, whole.size() - 10)).found);
  EXPECT_FALSE(Transfer(whole.substr(0, 100)).found);
}

// A 16-bit TIFF exported linear with its profile, and a PNG whose iCCP profile is linear, are read
// as linear (the PNG's iCCP chunk used to count as sRGB whatever it held); a gamma profile is not.
TEST_F(ImageIoTest, AnEmbeddedProfileStatesTheEncoding) {
  const auto write = [&](const std::string& name, const std::string& profile) {
    OIIO::ImageSpec spec(8, 6, 3, OIIO::TypeDesc::UINT16);
    spec.attribute("ICCProfile", OIIO::TypeDesc(OIIO::TypeDesc::UINT8, profile.size()),
                   profile.data());
    std::vector<std::uint16_t> pixels(8 * 6 * 3, 20000);
    auto out = OIIO::ImageOutput::create(Path(name));
    ASSERT_TRUE(out && out->open(Path(name), spec) &&
                out->write_image(OIIO::TypeDesc::UINT16, pixels.data()) && out->close());
  };
  write("linear.tif", IccProfile(Curv({})));
  StoredEncoding e = ReadStoredEncoding(Path("linear.tif"));
  EXPECT_TRUE(e.stated);
  EXPECT_EQ(e.encoding, Encoding::kLinear);
  EXPECT_EQ(e.statement, "ICC profile, linear");
  write("adobe.tif", IccProfile(Curv({563})));
  e = ReadStoredEncoding(Path("adobe.tif"));
  EXPECT_TRUE(e.stated);
  EXPECT_EQ(e.encoding, Encoding::kSrgb);
  EXPECT_EQ(e.statement, "ICC profile, gamma 2.2");
  write("linear.png", IccProfile(Curv({})));
  e = ReadStoredEncoding(Path("linear.png"));
  EXPECT_TRUE(e.stated);
  EXPECT_EQ(e.encoding, Encoding::kLinear);
  EXPECT_EQ(e.statement, "ICC profile, linear");
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

// EXIF orientation: every code read as the Exif standard (CIPA DC-008, tag 274) defines it, whole
// and in bands. OpenImageIO's ImageBufAlgo::reorient agrees on six codes; on 5 and 7 it swaps the
// two (OpenImageIO issue #4661, fixed after 2.5), which is why iphong maps pixels itself.
class OrientationTest : public ImageIoTest {
 protected:
  // A float TIFF of `stored` stating `orientation` (TIFF's own tag 274; JPEG carries it in Exif).
  void WriteStated(const std::string& path, const ImageF& stored, int orientation) {
    OIIO::ImageSpec spec(stored.width, stored.height, stored.channels, OIIO::TypeDesc::FLOAT);
    spec.attribute("Orientation", orientation);
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out && out->open(path, spec) &&
                out->write_image(OIIO::TypeDesc::FLOAT, stored.pixels.data()) && out->close());
  }
  // The standard's table: where the stored 0th row and 0th column are seen.
  static ImageF Standard(const ImageF& stored, int orientation) {
    enum Side { kTop, kBottom, kLeft, kRight };
    const Side row0[9] = {kTop, kTop, kTop, kBottom, kBottom, kLeft, kRight, kRight, kLeft};
    const Side col0[9] = {kLeft, kLeft, kRight, kRight, kLeft, kTop, kTop, kBottom, kBottom};
    const bool sideways = row0[orientation] == kLeft || row0[orientation] == kRight;
    const int w = stored.width, h = stored.height;
    ImageF shown(sideways ? h : w, sideways ? w : h, stored.channels);
    for (int sy = 0; sy < h; ++sy) {
      for (int sx = 0; sx < w; ++sx) {
        int x, y;
        if (!sideways) {
          y = row0[orientation] == kTop ? sy : h - 1 - sy;
          x = col0[orientation] == kLeft ? sx : w - 1 - sx;
        } else {
          x = row0[orientation] == kLeft ? sy : h - 1 - sy;
          y = col0[orientation] == kTop ? sx : w - 1 - sx;
        }
        for (int c = 0; c < stored.channels; ++c) shown.at(x, y)[c] = stored.at(sx, sy)[c];
      }
    }
    return shown;
  }
  // What OpenImageIO's reorient shows.
  static ImageF Reoriented(const std::string& path) {
    OIIO::ImageBuf file(path);
    OIIO::ImageBuf shown = OIIO::ImageBufAlgo::reorient(file);
    const OIIO::ImageSpec& spec = shown.spec();
    ImageF image(spec.width, spec.height, spec.nchannels);
    EXPECT_TRUE(shown.get_pixels(shown.roi(), OIIO::TypeDesc::FLOAT, image.pixels.data()));
    return image;
  }
};

TEST_F(OrientationTest, EveryCodeIsReadAsViewersShowIt) {
  const ImageF stored = Ramp(7, 4);
  for (int orientation = 1; orientation <= 8; ++orientation) {
    SCOPED_TRACE("orientation " + std::to_string(orientation));
    const std::string path = Path("o" + std::to_string(orientation) + ".tif");
    WriteStated(path, stored, orientation);
    const ImageF expected = Standard(stored, orientation);
    ASSERT_EQ(expected.width, OrientationSwapsAxes(orientation) ? 4 : 7);
    if (orientation != 5 && orientation != 7) {
      EXPECT_EQ(Reoriented(path).pixels, expected.pixels);
    }
    const ImageHeader header = ReadImageHeader(path);
    EXPECT_EQ(header.orientation, orientation);
    EXPECT_EQ(header.width, expected.width);
    EXPECT_EQ(header.height, expected.height);
    const ImageF read = ReadImage(path);
    ASSERT_EQ(read.width, expected.width);
    ASSERT_EQ(read.height, expected.height);
    EXPECT_EQ(read.pixels, expected.pixels);
    // Bands of displayed rows, of every height, give the same rows.
    for (int band = 1; band <= expected.height; ++band) {
      ImageRowReader reader(path);
      for (int y0 = 0; y0 < expected.height; y0 += band) {
        const int y1 = std::min(expected.height, y0 + band);
        const ImageF rows = reader.ReadRows(y0, y1);
        ASSERT_EQ(rows.width, expected.width);
        for (int y = y0; y < y1; ++y) {
          for (int x = 0; x < rows.width; ++x) {
            for (int c = 0; c < 3; ++c) {
              ASSERT_EQ(rows.at(x, y - y0)[c], expected.at(x, y)[c])
                  << x << "," << y << " band " << band;
            }
          }
        }
      }
    }
    // Another orientation imposed (a capture reads every photo as its first): the stored pixels
    // as that one shows them, whatever this file states.
    const ImageF upright = ReadImage(path, {}, {}, 1);
    EXPECT_EQ(upright.pixels, stored.pixels);
    ImageHeader seen;
    ReadImage(
        path, {}, [&](const ImageHeader& h) { seen = h; }, 6);
    EXPECT_EQ(seen.width, 4);
    EXPECT_EQ(seen.orientation, orientation);  // what the file states
    EXPECT_EQ(ImageRowReader(path, 1).ReadRows(0, 4).pixels, stored.pixels);
  }
  EXPECT_EQ(DescribeOrientation(6), "turned 90° clockwise");
}

// An EXR of several layers (Blender's multilayer output) lists its passes in name order: its
// first three channels were read as the picture, here the AO pass. Its colour layer is read, whole
// and in bands; two colour layers neither of which is the beauty pass are refused, naming them.
TEST_F(ImageIoTest, ALayeredExrIsReadAsItsColourLayer) {
  const int w = 6, h = 5;
  const auto write = [&](const std::string& name, const std::vector<std::string>& channels) {
    OIIO::ImageSpec spec(w, h, static_cast<int>(channels.size()), OIIO::TypeDesc::FLOAT);
    spec.channelnames = channels;
    spec.alpha_channel = -1;
    std::vector<float> data(std::size_t(w) * h * channels.size());
    for (std::size_t i = 0; i < data.size(); ++i) {
      const std::size_t c = i % channels.size();  // each channel's values its own
      data[i] = static_cast<float>(100 * c + i / channels.size());
    }
    auto out = OIIO::ImageOutput::create(Path(name));
    ASSERT_TRUE(out && out->open(Path(name), spec) &&
                out->write_image(OIIO::TypeDesc::FLOAT, data.data()) && out->close());
  };
  // The value of channel `name` at pixel i as this file reads back through OpenImageIO itself.
  const auto stored = [&](const std::string& path, const std::string& name, std::size_t i) {
    auto in = OIIO::ImageInput::open(path);
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<float> all(std::size_t(w) * h * spec.nchannels);
    in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data());
    const auto it = std::find(spec.channelnames.begin(), spec.channelnames.end(), name);
    return all[i * spec.nchannels + (it - spec.channelnames.begin())];
  };
  write("layers.exr", {"ViewLayer.AO.R", "ViewLayer.AO.G", "ViewLayer.AO.B", "ViewLayer.Combined.R",
                       "ViewLayer.Combined.G", "ViewLayer.Combined.B", "ViewLayer.Combined.A",
                       "ViewLayer.Depth.Z"});
  const ImageHeader header = ReadImageHeader(Path("layers.exr"));
  EXPECT_EQ(header.layer, "ViewLayer.Combined");
  EXPECT_EQ(header.channels, 4);
  EXPECT_EQ(header.alpha_channel, 3);
  const ImageF read = ReadImage(Path("layers.exr"));
  ASSERT_EQ(read.channels, 4);
  const ImageF rows = ImageRowReader(Path("layers.exr")).ReadRows(0, h);
  for (std::size_t i = 0; i < std::size_t(w) * h; ++i) {
    int c = 0;
    for (const char* suffix : {"R", "G", "B", "A"}) {
      const float want = stored(Path("layers.exr"), std::string("ViewLayer.Combined.") + suffix, i);
      ASSERT_EQ(read.pixels[4 * i + c], want) << i << suffix;
      ASSERT_EQ(rows.pixels[4 * i + c], want) << i << suffix;
      ++c;
    }
  }
  write("passes.exr",
        {"diffuse.R", "diffuse.G", "diffuse.B", "specular.R", "specular.G", "specular.B"});
  try {
    ReadImage(Path("passes.exr"));
    ADD_FAILURE() << "two colour passes were read as one picture";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("holds 2 colour layers (diffuse, specular) and none is "
                                         "the picture"),
              std::string::npos)
        << e.what();
  }
  // One layer, or layers without colour: every channel from the first, as before.
  write("normal.exr", {"Normal.X", "Normal.Y", "Normal.Z", "Depth.Z"});
  EXPECT_EQ(ReadImageHeader(Path("normal.exr")).channels, 4);
  EXPECT_EQ(ReadImageHeader(Path("normal.exr")).layer, "");
}

// OpenEXR keeps a data window inside a display window (a renderer's image cropped to what its
// light lit, or overscan beyond it). Viewers show the display window, black where there are no
// data, and so does iphong, whole and in bands, scan-line or tiled: before, the data window was
// read as the image (a capture's mask "is 96x96, the images are 82x82"), bands of such a file
// could not be read, and bands of any tiled file crashed inside OpenImageIO 2.4 (SIGFPE).
TEST_F(ImageIoTest, ImagesAreTheirDisplayWindowWholeAndInBands) {
  const int w = 10, h = 9;
  struct Case {
    const char* name;
    int x, y, width, height;  // the data window in display coordinates
    int tile;                 // 0: scan lines
  };
  const Case cases[] = {{"inside.exr", 3, 2, 5, 4, 0},       {"overscan.exr", -2, -3, 14, 15, 0},
                        {"corner.exr", 6, 5, 7, 8, 0},       {"tiled.exr", 0, 0, w, h, 4},
                        {"tiled_inside.exr", 1, 3, 7, 5, 2}, {"tiled_tif.tif", 0, 0, w, h, 16}};
  for (const Case& k : cases) {
    SCOPED_TRACE(k.name);
    OIIO::ImageSpec spec(k.width, k.height, 3, OIIO::TypeDesc::FLOAT);
    if (std::string(k.name).find(".exr") != std::string::npos) {
      spec.x = k.x + 100, spec.y = k.y + 200;  // a display window with an origin of its own
      spec.full_x = 100, spec.full_y = 200, spec.full_width = w, spec.full_height = h;
    }
    if (k.tile > 0) spec.tile_width = spec.tile_height = k.tile;
    std::vector<float> data(std::size_t(k.width) * k.height * 3);
    ImageF expected(w, h, 3);
    for (int y = 0; y < k.height; ++y) {
      for (int x = 0; x < k.width; ++x) {
        for (int c = 0; c < 3; ++c) {
          const float v = 1 + x + 100 * y + 10000 * c;
          data[(std::size_t(y) * k.width + x) * 3 + c] = v;
          const int dx = k.x + x, dy = k.y + y;
          if (dx >= 0 && dx < w && dy >= 0 && dy < h) expected.at(dx, dy)[c] = v;
        }
      }
    }
    const std::string path = Path(k.name);
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out && out->open(path, spec) &&
                out->write_image(OIIO::TypeDesc::FLOAT, data.data()) && out->close());
    const OIIO::ImageSpec stored = OIIO::ImageInput::open(path)->spec();
    if (std::string(k.name).find(".exr") != std::string::npos) {
      ASSERT_EQ(stored.x, spec.x);  // the file keeps what this case is about
      ASSERT_EQ(stored.full_width, w);
      ASSERT_EQ(stored.tile_width, k.tile);
    }
    const ImageHeader header = ReadImageHeader(path);
    EXPECT_EQ(header.width, w);
    EXPECT_EQ(header.height, h);
    const ImageF read = ReadImage(path);
    ASSERT_EQ(read.width, w);
    ASSERT_EQ(read.height, h);
    EXPECT_EQ(read.pixels, expected.pixels);
    for (int band = 1; band <= h; band += 2) {
      ImageRowReader reader(path);
      ASSERT_EQ(reader.header().width, w);
      for (int y0 = 0; y0 < h; y0 += band) {
        const int y1 = std::min(h, y0 + band);
        const ImageF rows = reader.ReadRows(y0, y1);
        ASSERT_EQ(rows.width, w);
        ASSERT_EQ(rows.height, y1 - y0);
        const std::vector<float> want(expected.pixels.begin() + std::size_t(y0) * w * 3,
                                      expected.pixels.begin() + std::size_t(y1) * w * 3);
        EXPECT_EQ(rows.pixels, want) << "rows " << y0 << ".." << y1;
      }
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
