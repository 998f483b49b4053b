// Capture folders of every layout: which images, lights, mask and encoding are found, in which
// order, and the one-line errors when they do not match.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "error_of.h"
#include "io/calibration_picture.h"
#include "io/capture.h"
#include "io/capture_bands.h"
#include "io/dataset.h"
#include "io/dataset_text.h"
#include "io/image_internal.h"
#include "io/image_io.h"

namespace iphong::io {
namespace {
namespace fs = std::filesystem;
using test::ErrorOf;

class Capture : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("iphong-capture-" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(root_);
    dir_ = root_ / "obj";
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(root_); }
  void Write(const fs::path& path, const std::string& text) const { std::ofstream(path) << text; }
  // A 4x3 image whose red channel is `value` everywhere.
  void Image(const fs::path& path, float value, int bits = 8) const {
    ImageF image(4, 3, 3, value);
    WriteImage(path.string(), image, {bits, Encoding::kLinear});
  }
  fs::path root_, dir_;
};

const char* kTwelveLights =
    "12\n"
    "0.40 0.48 0.78\n0.10 0.16 0.98\n-0.07 0.18 0.98\n-0.13 0.43 0.89\n-0.33 0.49 0.81\n"
    "-0.11 0.54 0.84\n0.24 0.41 0.88\n0.06 0.42 0.91\n0.13 0.34 0.93\n0.03 0.34 0.94\n"
    "0.10 0.05 0.99\n-0.16 0.35 0.92\n";

TEST(NaturalOrder, NumbersCompareAsNumbers) {
  std::vector<std::string> names = {"cat.10.tga", "cat.2.tga",    "cat.mask.tga", "cat.0.tga",
                                    "cat.1.tga",  "IMG_0009.JPG", "img_10.jpg",   "cat.002.tga"};
  std::sort(names.begin(), names.end(), NaturalLess);
  EXPECT_EQ(names,
            (std::vector<std::string>{"cat.0.tga", "cat.1.tga", "cat.002.tga", "cat.2.tga",
                                      "cat.10.tga", "cat.mask.tga", "IMG_0009.JPG", "img_10.jpg"}));
}

TEST(LightFiles, WhatIsWrittenReadsBack) {
  const std::vector<Vec3d> directions = {Vec3d(0.123456789, -0.5, 0.857), Vec3d(1e-7, 0.6, 0.8),
                                         Vec3d(0, 0, 1)};
  const std::vector<std::string> names = {"chrome.0.tga", "IMG 02.jpg", "003.png"};
  const LightFile lp = ParseLightFile(FormatLp(names, directions), "lights.lp", 0, nullptr);
  EXPECT_EQ(lp.format, "RTI .lp");
  EXPECT_EQ(lp.image_names, names);
  const std::vector<Vec3d> triples =
      ParseTriples(FormatTriples(directions), "light_directions.txt", 3);
  for (std::size_t j = 0; j < 3; ++j) {
    // Unit after reading (the readers normalize); 9 significant digits survive the text.
    EXPECT_LT((lp.directions[j] - directions[j].normalized()).norm(), 1e-8);
    EXPECT_LT((triples[j] - directions[j]).norm(), 1e-8);
  }
  EXPECT_THROW(FormatLp({"a.png"}, directions), std::invalid_argument);
}

TEST(LightFiles, EveryFormatGivesTheSameDirections) {
  const std::string plain = "0 0 1\n0.6 0 0.8\n0 0.6 0.8\n";
  const LightFile a = ParseLightFile(plain, "light_directions.txt", 0, nullptr);
  EXPECT_EQ(a.format, "directions");
  const LightFile b =
      ParseLightFile("3\n0, 0, 1\n0.6, 0, 0.8\n0,0.6,0.8\n", "lights.txt", 3, nullptr);
  EXPECT_EQ(b.format, "count + directions");
  const LightFile c = ParseLightFile(
      "3\nC:\\capture\\jpeg-exports\\IMG 01.jpg 0 0 1\nIMG 02.jpg 0.6 0 0.8\nIMG_03.jpg 0 0.6 "
      "0.8\n",
      "rig.lp", 0, nullptr);
  EXPECT_EQ(c.format, "RTI .lp");
  // Names that start like numbers are still names.
  EXPECT_EQ(
      ParseLightFile("3\n001.png 0 0 1\n002.png 0.6 0 0.8\n003.png 0 0.6 0.8\n", "d.lp", 0, nullptr)
          .image_names[1],
      "002.png");
  EXPECT_EQ(c.image_names, (std::vector<std::string>{"C:\\capture\\jpeg-exports\\IMG 01.jpg",
                                                     "IMG 02.jpg", "IMG_03.jpg"}));
  // AliceVision's frame: y down, z away from the camera.
  const LightFile d = ParseLightFile(
      R"({"lights": [{"lightId": 0, "type": "directional", "direction": [0, 0, -1], "intensity": [1, 2, 3]},
                     {"lightId": 1, "type": "directional", "direction": [0.6, 0, -0.8], "intensity": 1},
                     {"lightId": 2, "type": "directional", "direction": [0, -0.6, -0.8], "intensity": [1, 1, 1]}]})",
      "lights.json", 0, nullptr);
  EXPECT_EQ(d.format, "AliceVision JSON");
  EXPECT_EQ(d.intensities[0], Vec3d(1, 2, 3));
  for (const LightFile* f : {&b, &c, &d}) {
    ASSERT_EQ(f->directions.size(), 3u);
    for (int i = 0; i < 3; ++i) EXPECT_LT((f->directions[i] - a.directions[i]).norm(), 1e-12);
  }
}

// numpy.savetxt(header=...) writes "# ..." first; annotated exports put comments anywhere. A
// comment keeps the line numbers of the lines after it.
TEST(LightFiles, CommentLinesAreSkipped) {
  const LightFile a = ParseLightFile("# lx ly lz\n0 0 1\n  # the ring\n0.6 0 0.8\n0 0.6 0.8\n",
                                     "light_directions.txt", 3, nullptr);
  EXPECT_EQ(a.format, "directions");
  ASSERT_EQ(a.directions.size(), 3u);
  EXPECT_LT((a.directions[1] - Vec3d(0.6, 0, 0.8)).norm(), 1e-12);
  EXPECT_EQ(
      ParseLightFile("# made by hand\n2\na.png 0 0 1\nb.png 0.6 0 0.8\n", "rig.lp", 0, nullptr)
          .image_names,
      (std::vector<std::string>{"a.png", "b.png"}));
  EXPECT_EQ(ParseTriples("# r g b\n1 1 1\n2 2 2\n", "light_intensities.txt", 2)[1], Vec3d(2, 2, 2));
  EXPECT_EQ(ParseFilenames("# photos\n001.png\n002.png\n", "filenames.txt", 10).size(), 2u);
  EXPECT_EQ(ErrorOf([] { ParseTriples("# r g b\n1 1 1\n2 2\n", "light_intensities.txt", 2); }),
            "light_intensities.txt:3: expected 3 numbers, got '2 2'");
}

TEST(LightFiles, CountsThatDisagreeAreNamed) {
  EXPECT_EQ(
      ErrorOf([] { ParseLightFile("4\n0 0 1\n0.6 0 0.8\n0 0.6 0.8\n", "lights.txt", 0, nullptr); }),
      "lights.txt:1: says 4 lights on its first line but lists 3");
  EXPECT_EQ(ErrorOf([] { ParseLightFile("0 0 1\n0.6 0 0.8\n0 0.6 0.8\n", "l.txt", 4, nullptr); }),
            "l.txt: has 3 lights for 4 images");
  EXPECT_EQ(ErrorOf([] { ParseLightFile("0\n", "rig.lp", 0, nullptr); }),
            "rig.lp: lists no lights");
  EXPECT_EQ(
      ErrorOf([] { ParseLightFile("2\nIMG_01.jpg 0 0\nb.jpg 1 0 0\n", "rig.lp", 0, nullptr); }),
      "rig.lp:2: expected 'filename lx ly lz', got 'IMG_01.jpg 0 0'");
  EXPECT_NE(ErrorOf([] {
              ParseLightFile(R"({"lights": [{"direction": [0, 0, 1], "colour": 1}]})",
                             "lights.json", 0, nullptr);
            }).find("lights.json: lights[0]"),
            std::string::npos);
}

TEST_F(Capture, UwLayoutRunsAsItIs) {
  // UW: <obj>.<i>.tga, <obj>.mask.tga, one lights.txt beside the objects' folders.
  Write(root_ / "lights.txt", kTwelveLights);
  for (int i = 11; i >= 0; --i) Image(dir_ / ("obj." + std::to_string(i) + ".tga"), 0.1f * (i % 5));
  Image(dir_ / "obj.mask.tga", 1);
  const CaptureFiles c = FindCapture(dir_.string(), {});
  EXPECT_EQ(c.layout, "folder");
  EXPECT_EQ(c.order, "natural order");
  ASSERT_EQ(c.names.size(), 12u);
  EXPECT_EQ(c.names[2], "obj.2.tga");  // not obj.10.tga, where ls puts it
  EXPECT_EQ(c.names[11], "obj.11.tga");
  EXPECT_EQ(fs::path(c.lights_path), (dir_ / ".." / "lights.txt").lexically_normal());
  // A trailing separator names the same folder, with the same parent.
  EXPECT_EQ(FindCapture(dir_.string() + "/", {}).lights_path, c.lights_path);
  EXPECT_EQ(c.lights_format, "count + directions");
  EXPECT_EQ(fs::path(c.mask_path).filename(), "obj.mask.tga");
  EXPECT_EQ(c.light_intensities[5], Vec3d::Ones());

  // The names people give masks, best first.
  fs::rename(dir_ / "obj.mask.tga", dir_ / "obj_mask.png");
  EXPECT_EQ(fs::path(FindCapture(dir_.string(), {}).mask_path).filename(), "obj_mask.png");
  Image(dir_ / "mask.tga", 1);
  EXPECT_EQ(fs::path(FindCapture(dir_.string(), {}).mask_path).filename(), "mask.tga");

  // A light too few: the count, the folder and the images found.
  Write(root_ / "lights.txt", "3\n0 0 1\n0.6 0 0.8\n0 0.6 0.8\n");
  EXPECT_EQ(ErrorOf([&] { FindCapture(dir_.string(), {}); }),
            (dir_ / ".." / "lights.txt").lexically_normal().string() + ": has 3 lights, but " +
                dir_.string() +
                " holds 12 images (obj.0.tga ... obj.11.tga): a light missing from the file or "
                "a photo too many; to choose the photos, list them in light order in a file "
                "given with --images LIST");
}

TEST_F(Capture, AMaskNamedOnTheCommandLineIsNotALightImage) {
  Write(dir_ / "lights.txt", "0 0 1\n0.6 0 0.8\n0 0.6 0.8\n");
  for (int i = 1; i <= 3; ++i) Image(dir_ / ("shot" + std::to_string(i) + ".png"), 0.2f);
  Image(dir_ / "matte.png", 1);  // a name no rule knows as a mask's
  EXPECT_NE(ErrorOf([&] { FindCapture(dir_.string(), {}); }).find("holds 4 images"),
            std::string::npos);
  CaptureOptions options;
  options.mask = (dir_ / "matte.png").string();
  const CaptureFiles c = FindCapture(dir_.string(), options);
  EXPECT_EQ(c.names, (std::vector<std::string>{"shot1.png", "shot2.png", "shot3.png"}));
  EXPECT_EQ(c.mask_path, options.mask);
}

TEST_F(Capture, RtiLpNamesTheImagesWhereverRtiBuilderWroteThem) {
  fs::create_directories(dir_ / "assembly-files");
  std::string lp = "3\n";
  const char* directions[] = {"0 0 1", "0.6 0 0.8", "0 0.6 0.8"};
  for (int i = 0; i < 3; ++i) {
    const std::string name = "IMG_" + std::to_string(9 - i) + ".png";  // not in natural order
    Image(dir_ / name, 0.2f);
    lp += "C:\\Users\\someone\\capture\\jpeg-exports\\" + name + " " + directions[i] + "\n";
  }
  Write(dir_ / "assembly-files" / "capture.lp", lp);
  CaptureOptions options;
  options.lights = (dir_ / "assembly-files" / "capture.lp").string();
  const CaptureFiles c = FindCapture(dir_.string(), options);
  EXPECT_EQ(c.layout, "RTI .lp");
  ASSERT_EQ(c.paths.size(), 3u);
  EXPECT_EQ(fs::path(c.paths[0]).filename(), "IMG_9.png");  // the .lp's order
  EXPECT_TRUE(fs::exists(c.paths[2]));

  fs::remove(dir_ / "IMG_8.png");
  EXPECT_NE(ErrorOf([&] { FindCapture(dir_.string(), options); })
                .find("capture.lp: names C:\\Users\\someone\\capture\\jpeg-exports\\IMG_8.png, "
                      "which is in neither"),
            std::string::npos);
}

TEST_F(Capture, EncodingIsWhatTheFileStatesElseLinear) {
  Image(dir_ / "plain.png", 0.5f);
  const StoredEncoding plain = ReadStoredEncoding((dir_ / "plain.png").string());
  EXPECT_EQ(plain.bits, 8);
  // iphong's linear PNGs carry gAMA 1.
  EXPECT_TRUE(plain.stated);
  EXPECT_EQ(plain.encoding, Encoding::kLinear);
  EXPECT_EQ(plain.statement, "gAMA 1");
  // The same file without its gAMA chunk (4 length + 4 type + 4 data + 4 CRC bytes), as
  // DiLiGenT's PNGs are: OpenImageIO still calls it sRGB, the file states nothing.
  {
    std::ifstream in(dir_ / "plain.png", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    const std::size_t at = bytes.find("gAMA");
    ASSERT_NE(at, std::string::npos);
    bytes.erase(at - 4, 16);
    std::ofstream(dir_ / "bare.png", std::ios::binary) << bytes;
  }
  const StoredEncoding bare = ReadStoredEncoding((dir_ / "bare.png").string());
  EXPECT_FALSE(bare.stated) << bare.statement;
  EXPECT_EQ(ReadImage((dir_ / "bare.png").string()).width, 4);

  // Pictures of data (normals.png) state nothing, as DiLiGenT's Normal_gt.png: a gAMA 1 tag made
  // browsers show them washed out. The values are stored as they are.
  WriteImage((dir_ / "data.png").string(), ImageF(4, 3, 3, 0.5f), {16, Encoding::kData});
  const StoredEncoding data = ReadStoredEncoding((dir_ / "data.png").string());
  EXPECT_FALSE(data.stated) << data.statement;
  EXPECT_EQ(data.bits, 16);
  EXPECT_NEAR(ReadImage((dir_ / "data.png").string()).pixels[0], 0.5f, 1e-4f);

  WriteImage((dir_ / "srgb.png").string(), ImageF(4, 3, 3, 0.5f), {8, Encoding::kSrgb});
  const StoredEncoding srgb = ReadStoredEncoding((dir_ / "srgb.png").string());
  EXPECT_TRUE(srgb.stated);
  EXPECT_EQ(srgb.encoding, Encoding::kSrgb);

  WriteImage((dir_ / "photo.jpg").string(), ImageF(4, 3, 3, 0.5f), {8, Encoding::kSrgb});
  EXPECT_EQ(ReadStoredEncoding((dir_ / "photo.jpg").string()).statement, "JPEG");

  WriteImage((dir_ / "f.exr").string(), ImageF(4, 3, 3, 0.5f));
  EXPECT_TRUE(ReadStoredEncoding((dir_ / "f.exr").string()).header.is_float);

  CaptureFiles files;
  CaptureOptions forced;
  forced.encoding = "srgb";
  EXPECT_EQ(ChooseEncoding(files, forced, plain).encoding, Encoding::kSrgb);
  EXPECT_EQ(ChooseEncoding(files, {}, srgb).encoding, Encoding::kSrgb);
  StoredEncoding tga;
  tga.format = "targa";
  EXPECT_EQ(ChooseEncoding(files, {}, tga).encoding, Encoding::kLinear);
  EXPECT_NE(ChooseEncoding(files, {}, tga).reason.find("states no colour space"),
            std::string::npos);
}

TEST_F(Capture, CropAndDownscaleApplyToImagesMaskAndCounts) {
  Write(dir_ / "lights.txt", "0 0 1\n0.6 0 0.8\n0 0.6 0.8\n");
  for (int i = 1; i <= 3; ++i) {
    ImageF image(8, 6, 3, 0.25f);
    image.at(0, 0)[0] = 1.0f;  // one clipped pixel, outside the crop
    image.at(5, 3)[1] = 1.0f;  // one clipped pixel inside it
    WriteImage((dir_ / ("img" + std::to_string(i) + ".png")).string(), image,
               {16, Encoding::kLinear});
  }
  DatasetLoadOptions options;
  options.capture.crop = {2, 2, 6, 4};
  options.capture.downscale = 2;
  const Dataset d = LoadDataset(dir_.string(), options);
  ASSERT_EQ(d.images.size(), 3u);
  EXPECT_EQ(d.images[0].width, 3);
  EXPECT_EQ(d.images[0].height, 2);
  EXPECT_EQ(d.file_width, 8);
  // Block (crop cols 2-3, rows 0-1) holds the clipped green pixel: (3 × 0.25 + 1) / 4.
  EXPECT_NEAR(d.images[0].at(1, 0)[1], 0.4375f, 1e-4);
  EXPECT_EQ(d.image_counts[0].saturated, 1u);
  EXPECT_EQ(d.image_counts[0].pixels, 24u);
  EXPECT_NE(DescribeDataset(d).find("8x6 read as 3x2"), std::string::npos);

  options.capture.crop = {4, 4, 6, 4};
  EXPECT_NE(
      ErrorOf([&] { LoadDataset(dir_.string(), options); }).find("reaches outside the 8x6 image"),
      std::string::npos);
}

// Phone photos store the sensor's pixels and state how to turn them (EXIF orientation); the user
// draws the mask on the photo as displayed. Read turned, whole and in bands, they are the upright
// capture; a photo stating another turn is read as the first (a mounted camera does not turn).
TEST_F(Capture, ExifOrientationIsAppliedToEveryPhotoAsTheFirstStates) {
  const int w = 6, h = 4;  // displayed
  std::vector<ImageF> upright;
  Mask mask(w, h, true);
  mask.inside[0] = mask.inside[w + 2] = 0;
  for (int i = 0; i < 3; ++i) {
    ImageF image(w, h, 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) image.at(x, y)[c] = ((x + 3 * y + 5 * i + c) % 11) / 16.0f;
    upright.push_back(image);
  }
  const std::string lights = "0 0 1\n0.6 0 0.8\n0 0.6 0.8\n";
  ImageF mask_image(w, h, 1, 0.0f);
  for (int p = 0; p < w * h; ++p) mask_image.pixels[p] = mask.inside[p] ? 1.0f : 0.0f;
  auto make = [&](const fs::path& dir, const std::vector<int>& orientations) {
    fs::create_directories(dir);
    Write(dir / "lights.txt", lights);
    WriteImage((dir / "mask.png").string(), mask_image, {8, Encoding::kData});
    for (int i = 0; i < 3; ++i) {
      const int o = orientations[i];
      // The stored pixels a camera turned by `o` would have written (the first photo's turn:
      // all three share the sensor's frame).
      const int turn = orientations[0];
      const bool swap = OrientationSwapsAxes(turn);
      ImageF stored(swap ? h : w, swap ? w : h, 3);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          int sx, sy;
          internal::StoredPixel(turn, stored.width, stored.height, x, y, &sx, &sy);
          for (int c = 0; c < 3; ++c) stored.at(sx, sy)[c] = upright[i].at(x, y)[c];
        }
      const std::string path = (dir / ("img" + std::to_string(i + 1) + ".tif")).string();
      OIIO::ImageSpec spec(stored.width, stored.height, 3, OIIO::TypeDesc::FLOAT);
      spec.attribute("Orientation", o);
      auto out = OIIO::ImageOutput::create(path);
      ASSERT_TRUE(out && out->open(path, spec) &&
                  out->write_image(OIIO::TypeDesc::FLOAT, stored.pixels.data()) && out->close());
    }
  };
  make(root_ / "upright", {1, 1, 1});
  make(root_ / "turned", {6, 6, 6});
  make(root_ / "mixed", {8, 8, 1});  // the third photo's sensor flipped its statement
  const ObservationSet reference = LoadObservations((root_ / "upright").string());
  EXPECT_EQ(DescribeDataset(reference.dataset).find("EXIF"), std::string::npos);
  for (const char* name : {"turned", "mixed"}) {
    SCOPED_TRACE(name);
    const std::string dir = (root_ / name).string();
    const ObservationSet set = LoadObservations(dir);
    EXPECT_EQ(set.observations.pixels, reference.observations.pixels);
    EXPECT_EQ(set.observations.values, reference.observations.values);
    const Dataset whole = LoadDataset(dir);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(whole.images[i].pixels, upright[i].pixels);
    CaptureBands bands(dir, {});
    for (int y0 = 0; y0 < h; y0 += 3) {
      const solve::PhotometricData band = bands.ReadBand(y0, std::min(h, y0 + 3), true);
      for (std::size_t q = 0; q < band.pixel_count(); ++q) {
        const int p = band.pixels[q] + y0 * w;
        const auto at = std::find(reference.observations.pixels.begin(),
                                  reference.observations.pixels.end(), p) -
                        reference.observations.pixels.begin();
        for (int k = 0; k < 9; ++k)
          EXPECT_EQ(band.pixel(q)[k], reference.observations.pixel(at)[k]) << p;
      }
    }
    const std::string said = DescribeDataset(set.dataset);
    const std::string counts = DescribeImageCounts(set.dataset);
    if (std::string(name) == "turned") {
      EXPECT_NE(said.find("EXIF orientation 6 of img1.tif applied to every photo: turned 90° "
                          "clockwise (stored 4x6)"),
                std::string::npos)
          << said;
      EXPECT_EQ(counts.find("EXIF"), std::string::npos) << counts;
    } else {
      EXPECT_NE(counts.find("1 of 3 images state another EXIF orientation than img1.tif "
                            "(img3.tif: as stored)"),
                std::string::npos)
          << counts;
      EXPECT_NE(DescribeImageCounts(bands.dataset()).find("1 of 3 images state another"),
                std::string::npos);
    }
  }
}

// The calibration picture numbers images as the folder's names do.
TEST(ImageLabels, TheFilesOwnNumbersElsePositions) {
  using V = std::vector<std::string>;
  EXPECT_EQ(ImageLabels({"cat.0.tga", "cat.1.tga", "cat.11.tga"}), (V{"0", "1", "11"}));
  EXPECT_EQ(ImageLabels({"001.png", "002.png", "010.png"}), (V{"1", "2", "10"}));
  EXPECT_EQ(ImageLabels({"IMG_0013.JPG", "IMG_0014.JPG"}), (V{"13", "14"}));
  // The last runs of digits repeat: positions.
  EXPECT_EQ(ImageLabels({"shot3_v2.png", "shot4_v2.png"}), (V{"1", "2"}));
  EXPECT_EQ(ImageLabels({"front.png", "side7.png"}), (V{"1", "2"}));
  EXPECT_EQ(ImageLabels({"a/0.png", "b/00.png"}), (V{"1", "2"}));  // both are 0
}

}  // namespace
}  // namespace iphong::io
