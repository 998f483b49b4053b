// Scene files, datasets and meshes on disk: round trips and one-line errors naming the file.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "error_of.h"
#include "geometry/primitives.h"
#include "io/dataset.h"
#include "io/dataset_write.h"
#include "io/files.h"
#include "io/mesh_io.h"
#include "io/output_folder.h"
#include "io/scene_file.h"
#include "real_data_dir.h"

namespace iphong::io {
namespace {
namespace fs = std::filesystem;

class TempDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("iphong-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  void Write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
  }
  fs::path dir_;
};

using test::ErrorOf;

// A render output, as `iphong render` commits it.
void WriteDataset(const std::string& dir, const SceneFile& f, const render::RenderOutput& out,
                  bool per_light) {
  OutputFolderOptions options;
  options.command = "render";
  OutputFolder folder(dir, options);
  WriteRenderOutput(folder, "", f.scene, f.options, out, f.output, per_light);
  folder.Commit();
}

const char* kMinimalScene = R"({"width": 32, "height": 24,
  "lights": [{"type": "directional", "direction": [0, 0, 1]}],
  "objects": [{"shape": "sphere", "radius": 0.5, "subdivisions": 2}]})";

TEST_F(TempDir, ParsesTheIssueSceneFixture) {
  const SceneFile f = LoadSceneFile(IPHONG_FIXTURES_DIR "/scenes/issue3_sphere.json");
  EXPECT_EQ(f.scene.camera.width, 256);
  EXPECT_EQ(f.scene.camera.extent, 2.0);
  ASSERT_EQ(f.scene.lighting.lights.size(), 1u);
  EXPECT_NEAR(f.scene.lighting.lights[0].direction_cam.norm(), 1.0, 1e-12);
  ASSERT_EQ(f.scene.objects.size(), 1u);
  EXPECT_EQ(f.scene.objects[0].mesh.triangle_count(), 81920u);
  EXPECT_EQ(f.scene.objects[0].material.kd, Vec3d(0.9, 0.2, 0.1));
  EXPECT_EQ(f.options.shading, render::Shading::kPhong);
  EXPECT_EQ(f.output.format, "exr");
}

TEST_F(TempDir, SceneErrorsNameTheFileAndTheField) {
  auto error = [&](const std::string& text) {
    Write("scene.json", text);
    return ErrorOf([&] { LoadSceneFile(Path("scene.json")); });
  };
  const std::string file = Path("scene.json") + ": ";
  EXPECT_EQ(error(R"({"lights": [{"direction": [0,0,1]}], "objects": [{"shape": "cone"}]})"),
            file +
                "objects[0].shape: unknown shape 'cone' (expected sphere, cylinder, torus, "
                "plane, box, heightfield, mesh)");
  EXPECT_EQ(error(R"({"objects": [{"shape": "sphere"}]})"), file + "missing field 'lights'");
  EXPECT_EQ(
      error(
          R"({"lights": [{"direction": [0,0,1]}], "objects": [{"shape": "sphere", "raduis": 1}]})"),
      file +
          "objects[0]: unknown field 'raduis' (valid: albedo_texture, center, material, name, "
          "radius, shape, subdivisions, transform)");
  EXPECT_EQ(
      error(
          R"({"lights": [{"direction": [0,0,1]}], "objects": [{"shape": "sphere", "radius": -1}]})"),
      file + "objects[0].radius: expected a number > 0");
  EXPECT_EQ(error(R"({"lights": [{"direction": [0,0]}], "objects": [{"shape": "sphere"}]})"),
            file + "lights[0].direction: expected 3 numbers");
  EXPECT_EQ(error(R"({"lights": [{"direction": [0,0,0]}], "objects": [{"shape": "sphere"}]})"),
            file + "lights[0]: light direction must be finite and non-zero, got [0, 0, 0]");
  EXPECT_EQ(
      error(
          R"({"lights": [{"direction": [0,0,1]}], "objects": [{"shape": "sphere", "material": "unobtainium"}]})")
          .rfind(file + "objects[0].material: unknown material preset 'unobtainium'", 0),
      0u);
  // NaN is not JSON: a syntax error with its line and column.
  EXPECT_NE(error("{\"lights\": [{\"direction\": [0, 0, 1]}],\n \"objects\": [{\"radius\": NaN}]}")
                .find("parse error at line 2, column"),
            std::string::npos);
  // A key given twice: JSON would keep one silently; the error names the key and where.
  EXPECT_EQ(error(R"({"lights": [{"direction": [0,0,1]}], "objects": [{"shape": "sphere"},
    {"shape": "sphere", "material": {"kd": 0.5, "ks": 0.2, "kd": 0.9}}]})"),
            file +
                "objects[1].material: the key 'kd' is given twice in one object; JSON keeps "
                "only one of them: remove the other");
  EXPECT_EQ(error(R"({"lights": [], "lights": [{"direction": [0,0,1]}], "objects": []})"),
            file +
                "the key 'lights' is given twice in one object; JSON keeps only one of them: "
                "remove the other");
  // The same key in two objects, or at two depths, is not repeated.
  EXPECT_EQ(error(R"({"lights": [{"direction": [0,0,1]}], "objects": [{"shape": "sphere",
    "name": "a"}, {"shape": "sphere", "name": "b"}]})"),
            "(no error)");
  EXPECT_EQ(ErrorOf([&] { LoadSceneFile(Path("absent.json")); }),
            Path("absent.json") + ": no such file");
}

TEST_F(TempDir, LightSetsRingAndHemisphere) {
  const SceneFile ring =
      ParseScene(R"({"lights": [{"type": "ring", "count": 12, "elevation_deg": 30}],
    "objects": [{"shape": "plane"}]})",
                 "ring", "");
  ASSERT_EQ(ring.scene.lighting.lights.size(), 12u);
  for (const auto& l : ring.scene.lighting.lights) EXPECT_NEAR(l.direction_cam.z(), 0.5, 1e-12);
  EXPECT_NEAR(ring.scene.lighting.lights[3].direction_cam.y(), std::cos(M_PI / 6), 1e-12);
  const SceneFile hemi =
      ParseScene(R"({"lights": [{"type": "hemisphere", "count": 96, "min_elevation_deg": 30}],
    "objects": [{"shape": "plane"}]})",
                 "hemi", "");
  ASSERT_EQ(hemi.scene.lighting.lights.size(), 96u);
  Vec3d mean = Vec3d::Zero();
  for (const auto& l : hemi.scene.lighting.lights) {
    EXPECT_GE(l.direction_cam.z(), 0.5 - 1e-12);
    mean += l.direction_cam / 96;
  }
  EXPECT_LT(std::hypot(mean.x(), mean.y()), 0.02);  // spread evenly around the view axis
}

TEST_F(TempDir, PerLightDatasetRoundTrip) {
  SceneFile f = ParseScene(R"({"width": 48, "height": 40, "ambient": 0.5,
    "lights": [{"type": "ring", "count": 5, "elevation_deg": 50, "intensity": [1, 0.9, 0.8]}],
    "objects": [{"shape": "torus", "ring_radius": 0.55, "tube_radius": 0.3,
                 "material": {"preset": "jade", "kd": [0.4, 0.5, 0.6]}}]})",
                           "torus", "");
  const render::RenderOutput out = render::Render(f.scene, f.options, true);
  for (const std::string format : {"exr", "png"}) {
    f.output.format = format;
    WriteDataset(Path("set-" + format), f, out, true);
    const Dataset d = LoadDataset(Path("set-" + format));
    ASSERT_EQ(d.images.size(), 5u);
    EXPECT_EQ(d.filenames[0], "001." + format);
    for (std::size_t j = 0; j < 5; ++j) {
      EXPECT_TRUE(d.light_directions[j].isApprox(f.scene.lighting.lights[j].direction_cam, 1e-8));
      EXPECT_TRUE(d.light_intensities[j].isApprox(Vec3d(1, 0.9, 0.8), 1e-8));
      const double tolerance = format == "exr" ? 0.0 : 0.5 / 65535 + 1e-7;
      for (std::size_t i = 0; i < out.per_light[j].pixels.size(); ++i) {
        ASSERT_NEAR(d.images[j].pixels[i], std::clamp(out.per_light[j].pixels[i], 0.0f, 1.0f),
                    tolerance);
      }
    }
    EXPECT_EQ(d.mask.inside, out.mask.inside);
    EXPECT_EQ(d.normal_gt.pixels, out.normal_cam.pixels);  // float -> double .mat -> float
    ASSERT_TRUE(d.material.has_value());
    EXPECT_EQ(d.material->material.ks, Vec3d::Constant(0.32));
    EXPECT_EQ(d.material->material.shininess, 12.8);
    EXPECT_EQ(d.material->ambient, Vec3d::Constant(0.5));
    EXPECT_TRUE(d.material->kd_known);
    EXPECT_TRUE(d.warnings.empty());
  }
}

TEST_F(TempDir, WritingRefusesForeignFoldersAndFailsCleanly) {
  SceneFile f = ParseScene(kMinimalScene, "minimal", "");
  const render::RenderOutput out = render::Render(f.scene, f.options, true);
  fs::create_directories(Path("out"));
  Write("out/notes.txt", "mine");
  // A folder iphong did not write is never used, let alone replaced.
  EXPECT_NE(ErrorOf([&] {
              WriteDataset(Path("out"), f, out, false);
            }).find("is not empty and was not written by iphong"),
            std::string::npos);
  EXPECT_EQ(ReadTextFile(Path("out/notes.txt")), "mine");
  EXPECT_FALSE(fs::exists(Path("out/image.exr")));
  WriteDataset(Path("new"), f, out, false);
  EXPECT_TRUE(fs::exists(Path("new/image.exr")));
  // A point light cannot go into the DiLiGenT layout: clear error, nothing written.
  f.scene.lighting.lights.push_back(reflectance::Light::Point(Vec3d(0, 0, 3), Vec3d::Ones(), true));
  EXPECT_NE(ErrorOf([&] { WriteDataset(Path("pl"), f, out, true); }).find("point light"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(Path("pl")));
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".iphong-partial"), std::string::npos);
  }
}

class BadDataset : public TempDir {
 protected:
  void SetUp() override {
    TempDir::SetUp();
    SceneFile f = ParseScene(kMinimalScene, "minimal", "");
    f.scene.lighting.lights.push_back(
        reflectance::Light::Directional(Vec3d(0.5, 0, 1), Vec3d::Ones()));
    const render::RenderOutput out = render::Render(f.scene, f.options, true);
    f.output.format = "png";
    WriteDataset(Path("d"), f, out, true);
  }
  std::string LoadError() const {
    return ErrorOf([&] { LoadDataset(Path("d")); });
  }
};

TEST_F(BadDataset, ShortLightFileNamesTheFile) {
  Write("d/light_directions.txt", "0 0 1\n");
  EXPECT_EQ(LoadError(),
            Path("d/light_directions.txt") + ": has 1 lines for 2 images in filenames.txt");
}

TEST_F(BadDataset, NanInLightFileNamesTheLine) {
  Write("d/light_directions.txt", "0 0 1\nnan 0 1\n");
  EXPECT_EQ(LoadError(), Path("d/light_directions.txt") + ":2: not a finite number: 'nan 0 1'");
  Write("d/light_directions.txt", "0 0 1\n0 1\n");
  EXPECT_EQ(LoadError(), Path("d/light_directions.txt") + ":2: expected 3 numbers, got '0 1'");
}

// Images identical inside the mask are named (the first pair), or "all" when every one is; images
// black or clipped at every pixel are alike by nature (a dome's lights behind the object) and are
// not called copies.
TEST(ImageCounts, IdenticalImagesAreNamedAndBlankOnesAreNot) {
  Dataset d;
  d.filenames = {"a.png", "b.png", "c.png", "d.png", "e.png"};
  d.image_counts.assign(5, {});
  for (std::size_t j = 0; j < 5; ++j) {
    d.image_counts[j].pixels = 100;
    d.image_counts[j].masked_hash = 1000 + j;
  }
  EXPECT_EQ(DescribeImageCounts(d), "");
  d.image_counts[3].masked_hash = d.image_counts[1].masked_hash;
  EXPECT_EQ(DescribeImageCounts(d),
            "1 of 5 images repeat another pixel for pixel inside the mask (b.png and d.png are "
            "identical): one photo saved under two names? Each light needs its own");
  d.image_counts[3].masked_hash = 1003;
  for (int j : {0, 4}) {  // black everywhere: equal hashes, not copies
    d.image_counts[j].black = 100;
    d.image_counts[j].masked_hash = 7;
  }
  EXPECT_EQ(DescribeImageCounts(d).find("repeat another"), std::string::npos)
      << DescribeImageCounts(d);
  for (auto& c : d.image_counts) c = ImageCounts{100, 0, 0, 1, 42};
  EXPECT_EQ(DescribeImageCounts(d),
            "all 5 images are identical inside the mask: the light did not change between the "
            "photographs, or one photo was saved under every name");
}

// An image a hundred times as bright as the median one for its light's intensity (another
// exposure, other units) is named, as is one negative on average; the intensities are taken in.
TEST(ImageCounts, ImagesBrightBeyondAnyShadingOrNegativeAreNamed) {
  Dataset d;
  d.filenames = {"a.exr", "b.exr", "c.exr", "d.exr"};
  d.image_counts.assign(4, {});
  d.light_intensities.assign(4, Vec3d::Ones());
  for (std::size_t j = 0; j < 4; ++j) {
    d.image_counts[j].pixels = 100;
    d.image_counts[j].masked_hash = j;
    d.image_counts[j].linear_sum = 40 + j;  // means 0.40 ... 0.43
  }
  EXPECT_EQ(DescribeImageCounts(d), "");
  d.image_counts[2].linear_sum = 40 * 255;  // stored in 0-255
  EXPECT_EQ(DescribeImageCounts(d),
            "1 of 4 images are more than 100 times as bright as the median image, after their "
            "lights' intensities (most: c.exr, 237 times): a photo at another exposure, or "
            "stored in other units (0-255 among 0-1)? Give its intensity (--intensities) or "
            "convert it");
  d.light_intensities[2] = Vec3d::Constant(255);  // its light said so: nothing to say
  EXPECT_EQ(DescribeImageCounts(d), "");
  d.image_counts[1].linear_sum = -5;
  EXPECT_EQ(DescribeImageCounts(d),
            "1 of 4 images are negative on average inside the mask (first: b.exr): a black level "
            "subtracted twice, or an offset? Light only adds; these values are read as dark");
}

// Images black on much of the mask are named; when the mask keeps the image's border and leaves
// a region inside out, the likely cause (a mask drawn the wrong way round) is said too.
TEST(ImageCounts, BlackImagesNameAMaskDrawnTheWrongWayRound) {
  Dataset d;
  for (int j = 0; j < 4; ++j) {
    ImageCounts c;
    c.pixels = 84;
    c.black = j < 2 ? 60 : 0;
    c.linear_sum = 10;
    c.masked_hash = j;
    d.image_counts.push_back(c);
    d.filenames.push_back("img" + std::to_string(j) + ".png");
    d.light_intensities.push_back(Vec3d::Ones());
  }
  d.files.mask_path = "mask.png";
  d.mask = Mask(10, 10, true);  // the border kept, a 4 x 4 region inside left out
  for (int y = 3; y < 7; ++y)
    for (int x = 3; x < 7; ++x) d.mask.inside[y * 10 + x] = 0;
  const std::string black =
      "2 of 4 images are black (0) on more than 10% of the mask (most: img0.png, 71.4%): "
      "under-exposed, or lights the object does not face";
  EXPECT_EQ(DescribeImageCounts(d),
            black +
                " (the mask keeps the image's border and leaves out a region inside it: drawn "
                "the wrong way round? Nonzero marks the object)");
  d.mask = Mask(10, 10, false);  // the object inside, the border left out: no hint
  for (int y = 3; y < 7; ++y)
    for (int x = 3; x < 7; ++x) d.mask.inside[y * 10 + x] = 1;
  EXPECT_EQ(DescribeImageCounts(d), black);
  d.files.mask_path.clear();
  d.mask = Mask(10, 10, true);
  EXPECT_EQ(DescribeImageCounts(d), black + " (there is no mask: the background counts; --mask)");
}

// An intensity file the images' brightness contradicts is named: each image's mean follows
// b·L_j × E_j (Lambert's law for the whole mask); the right file is silent, the same file in
// another order or inverted is not, and a file of equal intensities says nothing either way.
TEST(ImageCounts, AnIntensityFileTheImagesContradictIsNamed) {
  Dataset d;
  const int k = 12;
  const Vec3d b(0.05, -0.03, 0.4);  // the mask's mean albedo × normal
  d.files.intensities_from_file = true;
  d.files.intensities_source = "light_intensities.txt";
  for (int j = 0; j < k; ++j) {
    const double z = 0.95 - 0.5 * j / k, r = std::sqrt(1 - z * z);
    d.light_directions.push_back(Vec3d(r * std::cos(2.4 * j), r * std::sin(2.4 * j), z));
    d.light_intensities.push_back(Vec3d::Constant(0.5 + 0.1 * ((j * 7) % 12)));  // 0.5 … 1.6
    d.filenames.push_back("img" + std::to_string(j) + ".png");
    ImageCounts c;
    c.pixels = 1000;
    c.masked_hash = j;
    c.linear_sum = 1000 * b.dot(d.light_directions[j]) * d.light_intensities[j].mean();
    d.image_counts.push_back(c);
  }
  EXPECT_EQ(DescribeImageCounts(d), "");
  Dataset shuffled = d, inverted = d;
  // Read one line off (a header line, a light missing at the top).
  std::rotate(shuffled.light_intensities.begin(), shuffled.light_intensities.begin() + 1,
              shuffled.light_intensities.end());
  for (Vec3d& e : inverted.light_intensities) e = e.cwiseInverse();
  for (const Dataset* wrong : {&shuffled, &inverted}) {
    EXPECT_EQ(DescribeImageCounts(*wrong).rfind(
                  "light_intensities.txt: the images' brightness follows their lights' directions "
                  "worse with these intensities than with none (misfit ",
                  0),
              0u)
        << DescribeImageCounts(*wrong);
  }
  // Every other reading of the file (shifted by whole lines, reversed) is named too. Shifted by
  // five, the file fits better than no file (misfit 0.28 against 0.33) but worse than read back.
  for (int s = 1; s < k; ++s) {
    for (const bool reversed : {false, true}) {
      Dataset off = d;
      if (reversed) std::reverse(off.light_intensities.begin(), off.light_intensities.end());
      std::rotate(off.light_intensities.begin(), off.light_intensities.begin() + s,
                  off.light_intensities.end());
      EXPECT_EQ(DescribeImageCounts(off).rfind("light_intensities.txt: the images' brightness", 0),
                0u)
          << "shift " << s << (reversed ? " reversed" : "");
    }
  }
  Dataset fifth = d;
  std::rotate(fifth.light_intensities.begin(), fifth.light_intensities.begin() + 5,
              fifth.light_intensities.end());
  // The whole-mask fits by the normal equations, here: the RMS of y − L·b over the mean of y.
  const auto misfit = [&](const std::vector<Vec3d>& e) {
    Eigen::MatrixX3d l(k, 3);
    Eigen::VectorXd y(k);
    for (int j = 0; j < k; ++j) {
      l.row(j) = d.light_directions[j].transpose();
      y(j) = d.image_counts[j].linear_sum / d.image_counts[j].pixels / e[j].mean();
    }
    const Eigen::Vector3d fit = (l.transpose() * l).ldlt().solve(l.transpose() * y);
    return std::sqrt((y - l * fit).squaredNorm() / k) / y.mean();
  };
  const double as_listed = misfit(fifth.light_intensities);
  // Better than no file, so only the re-readings can name it.
  EXPECT_LT(as_listed, misfit(std::vector<Vec3d>(k, Vec3d::Ones())));
  char listed[16];
  std::snprintf(listed, sizeof listed, "%.3f", as_listed);
  EXPECT_EQ(DescribeImageCounts(fifth),
            "light_intensities.txt: the images' brightness follows their lights' directions "
            "better with these intensities read 5 lines further up (image 1 on line 8) than as "
            "listed (misfit 0.000 against " +
                std::string(listed) +
                " of the mean): is the file a line off from the images (a header line, a light "
                "missing at the top, images numbered from 0 and lights from 1)?");
  // Equal intensities fit as none does; point lights are not asked.
  Dataset equal = shuffled;
  for (Vec3d& e : equal.light_intensities) e = Vec3d::Constant(2);
  EXPECT_EQ(DescribeImageCounts(equal).find("worse with these intensities"), std::string::npos);
  shuffled.files.near.positions_path = "light_positions.txt";
  EXPECT_EQ(DescribeImageCounts(shuffled), "");
}

// A grey light's intensity is one number: the same in R, G and B. Two numbers are an error.
TEST_F(BadDataset, OneIntensityPerLineIsAGreyLight) {
  Write("d/light_intensities.txt", "2\n0.5 0.25 1\n");
  const Dataset d = LoadDataset(Path("d"));
  EXPECT_EQ(d.light_intensities[0], Vec3d(2, 2, 2));
  EXPECT_EQ(d.light_intensities[1], Vec3d(0.5, 0.25, 1));
  Write("d/light_intensities.txt", "2\n1 1\n");
  EXPECT_EQ(LoadError(), Path("d/light_intensities.txt") +
                             ":2: expected 3 numbers (or 1 for a grey light), got '1 1'");
}

TEST_F(BadDataset, ZeroIntensityIsAnError) {
  Write("d/light_intensities.txt", "1 1 1\n1 0 1\n");
  EXPECT_EQ(LoadError(), Path("d/light_intensities.txt") +
                             ":2: light intensities must be between 1e-30 and 1e30");
}

TEST_F(BadDataset, UnnormalizedDirectionsAreNormalizedWithAWarning) {
  Write("d/light_directions.txt", "0 0 2\n0.5 0 1\n");
  const Dataset d = LoadDataset(Path("d"));
  EXPECT_TRUE(d.light_directions[0].isApprox(Vec3d(0, 0, 1)));
  // One warning for the file, not one per light.
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_EQ(d.warnings[0], Path("d/light_directions.txt") +
                               ":1: light direction has length 2; normalized (as are 1 more of "
                               "the 2 directions)");
}

TEST_F(BadDataset, MissingOrCorruptImageNamesIt) {
  fs::remove(Path("d/002.png"));
  EXPECT_NE(LoadError().find("002.png"), std::string::npos);
  Write("d/002.png", "\x89PNG\r\n\x1a\n garbage");
  EXPECT_NE(LoadError().find("002.png"), std::string::npos);
}

TEST_F(BadDataset, SizeMismatchNamesTheFile) {
  fs::copy_file(Path("d/normals.png"), Path("d/mask.png"), fs::copy_options::overwrite_existing);
  EXPECT_EQ(LoadError().find(Path("d/mask.png")), std::string::npos);  // same size: fine
  ImageF small(8, 8, 3, 0.5f);
  fs::remove(Path("d/002.png"));
  WriteImage(Path("d/002.png"), small, {16, Encoding::kLinear});
  EXPECT_EQ(LoadError(), Path("d/002.png") + ": is 8x8, but 001.png is 32x24");
}

TEST_F(BadDataset, BadMaterialJsonNamesTheField) {
  Write("d/material.json", R"({"model": "phong", "ks": [0.1, -0.2, 0.1]})");
  EXPECT_EQ(LoadError(),
            Path("d/material.json") +
                ": material ks must be finite and >= 0 in every channel, got [0.1, -0.2, 0.1]");
  Write("d/material.json", "{\"model\": \"phong\",\n \"ks\": }");
  EXPECT_NE(LoadError().find(Path("d/material.json") + ": parse error at line 2"),
            std::string::npos);
}

TEST_F(TempDir, MeshSaveLoadRoundTrip) {
  const geometry::TriangleMesh sphere = geometry::MakeSphere(0.7, 3);
  std::vector<Vec3f> colors(sphere.positions.size(), Vec3f(0.2f, 0.4f, 0.6f));
  SaveMesh(Path("sphere.ply"), sphere, &colors);
  SaveMesh(Path("sphere.obj"), sphere);
  SaveMesh(Path("coloured.obj"), sphere, &colors);  // written by iphong: OpenMesh cannot
  for (const std::string name : {"sphere.ply", "sphere.obj", "coloured.obj"}) {
    const geometry::TriangleMesh back = LoadMesh(Path(name));
    ASSERT_EQ(back.positions.size(), sphere.positions.size()) << name;
    ASSERT_EQ(back.triangles.size(), sphere.triangles.size()) << name;
    for (std::size_t v = 0; v < sphere.positions.size(); ++v) {
      ASSERT_LT((back.positions[v] - sphere.positions[v]).norm(), 1e-5);
    }
    for (std::size_t t = 0; t < back.triangles.size(); ++t) {
      EXPECT_GT(back.corner_normals[3 * t].dot(sphere.corner_normals[3 * t]), 0.999);
    }
  }
  // Binary PLY, as promised.
  std::ifstream ply(Path("sphere.ply"), std::ios::binary);
  std::string header((std::istreambuf_iterator<char>(ply)), {});
  EXPECT_NE(header.find("format binary_little_endian"), std::string::npos);
  EXPECT_NE(header.find("property uchar red"), std::string::npos);
  // The OBJ's colours: sRGB of 0.2 linear is 0.4845 (124/255).
  std::ifstream obj(Path("coloured.obj"));
  std::string text((std::istreambuf_iterator<char>(obj)), {});
  EXPECT_NE(text.find(" 0.4863 0.6667 0.7961\n"), std::string::npos) << text.substr(0, 200);
  EXPECT_EQ(ErrorOf([&] { LoadMesh(Path("none.obj")); }), Path("none.obj") + ": no such file");
}

// The real DiLiGenT data beside the checkout (skipped when absent).

TEST(RealData, LoadsDiligentCrop8Ball) {
  const std::string dir = test::RealDataDir() + "/diligent-crop8/ball";
  if (!fs::exists(dir)) GTEST_SKIP() << "no real data at " << dir << " (set IPHONG_DATA_DIR)";
  const Dataset d = LoadDataset(dir);
  ASSERT_EQ(d.images.size(), 96u);
  EXPECT_EQ(d.width(), 172);
  EXPECT_EQ(d.height(), 172);
  ASSERT_EQ(d.normal_gt.width, 172);
  std::size_t inside = 0;
  for (std::size_t p = 0; p < d.mask.inside.size(); ++p) {
    if (!d.mask.inside[p]) continue;
    ++inside;
    const float* n = d.normal_gt.pixels.data() + 3 * p;
    ASSERT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-3);
  }
  EXPECT_GT(inside, 10000u);
  // The SPEC frame: at the top of the ball (small rows) the normals point up (+y).
  const float* top = d.normal_gt.pixels.data() + 3 * (30 * 172 + 86);
  EXPECT_GT(top[1], 0.5f);
  for (const Vec3d& l : d.light_directions) EXPECT_GT(l.z(), 0);
}

}  // namespace
}  // namespace iphong::io

namespace iphong::io {
namespace {

TEST_F(TempDir, AlbedoTextureModulatesKdThroughUv) {
  // A 2x1 texture: left half white, right half 0.25. On a plane seen head-on, uv runs with x.
  ImageF texture(2, 1, 3);
  for (int c = 0; c < 3; ++c) {
    texture.at(0, 0)[c] = 1.0f;
    texture.at(1, 0)[c] = 0.25f;
  }
  WriteImage(Path("tex.exr"), texture);
  const SceneFile f = ParseScene(R"({"width": 40, "height": 40,
    "lights": [{"direction": [0, 0, 1]}],
    "objects": [{"shape": "plane", "size": 2, "material": {"kd": 0.8, "ks": 0},
                 "albedo_texture": "tex.exr"}]})",
                                 "tex", dir_.string());
  const render::RenderOutput out = render::Render(f.scene, f.options, false);
  // Bilinear lookup with wrap-around: column c sees u = (c + 0.5)/40, texel x = 2u − 0.5.
  auto expected = [](int col) {
    const double x = 2 * (col + 0.5) / 40 - 0.5;
    const int x0 = static_cast<int>(std::floor(x));
    const double f = x - x0;
    auto texel = [](int i) { return ((i % 2) + 2) % 2 == 0 ? 1.0 : 0.25; };
    return 0.8 * ((1 - f) * texel(x0) + f * texel(x0 + 1));
  };
  for (int col : {3, 10, 19, 30, 37}) {
    EXPECT_NEAR(out.albedo.at(col, 20)[0], expected(col), 1e-6) << "column " << col;
    EXPECT_NEAR(out.image.at(col, 20)[0], expected(col), 1e-6);  // light along the normal
  }
  EXPECT_NEAR(out.albedo.at(10, 20)[0], 0.785, 1e-6);
  EXPECT_NE(ErrorOf([&] {
              ParseScene(R"({"lights": [{"direction": [0, 0, 1]}],
                "objects": [{"shape": "box", "albedo_texture": "tex.exr"}]})",
                         "box", dir_.string());
            }).find("needs a shape with uv coordinates"),
            std::string::npos);
}

TEST_F(TempDir, HeightFieldFromAnImage) {
  ImageF heights(3, 3, 1);
  heights.pixels = {0, 0, 0, 0, 1, 0, 0, 0, 0};  // a spike in the middle
  WriteImage(Path("h.exr"), heights);
  const SceneFile f = ParseScene(R"({"lights": [{"direction": [0, 0, 1]}],
    "objects": [{"shape": "heightfield", "image": "h.exr", "scale": 0.5, "size": [2, 2]}]})",
                                 "hf", dir_.string());
  const auto& mesh = f.scene.objects[0].mesh;
  ASSERT_EQ(mesh.positions.size(), 9u);
  EXPECT_DOUBLE_EQ(mesh.positions[4].z(), 0.5);
  EXPECT_DOUBLE_EQ(mesh.positions[0].z(), 0.0);
}

TEST_F(TempDir, MeshFileInASceneUsesItsNormalsAndTransform) {
  geometry::TriangleMesh sphere = geometry::MakeSphere(1.0, 3);
  SaveMesh(Path("ball.ply"), sphere);
  const SceneFile f =
      ParseScene(R"({"width": 64, "height": 64, "lights": [{"direction": [0, 0, 1]}],
    "objects": [{"shape": "mesh", "path": "ball.ply", "transform": {"scale": 0.5, "translate": [0.25, 0, 0]}}]})",
                 "mesh", dir_.string());
  const auto& mesh = f.scene.objects[0].mesh;
  for (std::size_t v = 0; v < mesh.positions.size(); v += 17) {
    EXPECT_NEAR((mesh.positions[v] - Vec3d(0.25, 0, 0)).norm(), 0.5, 1e-5);
  }
  EXPECT_EQ(
      ErrorOf([&] {
        ParseScene(
            R"({"lights": [{"direction": [0, 0, 1]}], "objects": [{"shape": "mesh", "path": "nope.obj"}]})",
            "m", dir_.string());
      }),
      "m: objects[0]: " + Path("nope.obj") + ": no such file");
}

TEST(Noise, ShotNoiseVarianceFollowsTheSignal) {
  // Poisson: variance = value / photons, so the noise grows with the signal.
  render::NoiseOptions noise;
  noise.shot_photons = 1000;
  for (float level : {0.1f, 0.4f}) {
    ImageF image(300, 300, 1, level);
    render::ApplyNoise(image, noise, 0);
    double mean = 0, var = 0;
    for (float v : image.pixels) mean += v;
    mean /= image.pixels.size();
    for (float v : image.pixels) var += (v - mean) * (v - mean);
    var /= image.pixels.size();
    EXPECT_NEAR(mean, level, 3e-4);
    EXPECT_NEAR(var, level / 1000.0, 0.05 * level / 1000.0);
  }
}

}  // namespace
}  // namespace iphong::io

namespace iphong::io {
namespace {

TEST_F(BadDataset, StreamingObservationsEqualLoadThenGather) {
  const Dataset d = LoadDataset(Path("d"));
  std::vector<const float*> images;
  for (const ImageF& image : d.images) images.push_back(image.pixels.data());
  const solve::PhotometricData gathered = solve::GatherObservations(
      images, d.width(), d.height(), d.mask, d.light_directions, d.light_intensities);
  const ObservationSet streamed = LoadObservations(Path("d"));
  EXPECT_EQ(streamed.observations.pixels, gathered.pixels);
  EXPECT_EQ(streamed.observations.values, gathered.values);
  EXPECT_TRUE(streamed.dataset.images.empty());
  EXPECT_EQ(streamed.dataset.normal_gt.pixels, d.normal_gt.pixels);
  // The same one-line errors as the full loader.
  Write("d/002.png", "\x89PNG\r\n\x1a\n garbage");
  EXPECT_NE(ErrorOf([&] { LoadObservations(Path("d")); }).find("002.png"), std::string::npos);
  ImageF small(8, 8, 3, 0.5f);
  fs::remove(Path("d/002.png"));
  WriteImage(Path("d/002.png"), small, {16, Encoding::kLinear});
  EXPECT_EQ(ErrorOf([&] { LoadObservations(Path("d")); }),
            Path("d/002.png") + ": is 8x8, but mask.png is 32x24");
}

}  // namespace
}  // namespace iphong::io
