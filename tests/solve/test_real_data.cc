// Published figures on the real DiLiGenT data beside the checkout (skipped when it is absent).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "io/dataset.h"
#include "real_data_dir.h"
#include "solve/metrics.h"
#include "solve/normals.h"

namespace iphong::solve {
namespace {

struct Object {
  const char* path;
  // DiLiGenT's baseline table, which is for the full-resolution 16-bit images; the 8-bit crops
  // shift Woodham's error by quantizing the dark observations (ball: 4.48 vs 4.16), so they are
  // not checked against it (< 0).
  double published_woodham_deg;
};
void PrintTo(const Object& o, std::ostream* os) { *os << o.path; }

class RealData : public ::testing::TestWithParam<Object> {
 protected:
  void SetUp() override {
    dir_ = test::RealDataDir() + "/" + GetParam().path;
    if (!std::filesystem::exists(dir_)) GTEST_SKIP() << "no real data at " << dir_;
    io::Dataset d = io::LoadDataset(dir_);
    std::vector<const float*> images;
    for (const ImageF& image : d.images) images.push_back(image.pixels.data());
    data_ = GatherObservations(images, d.width(), d.height(), d.mask, d.light_directions,
                               d.light_intensities);
    gt_ = d.normal_gt;
    mask_ = d.mask;
  }
  AngularErrorMetrics Run(const NormalOptions& o) {
    return CompareNormals(EstimateNormals(data_, o).normals, gt_, mask_);
  }
  std::string dir_;
  PhotometricData data_;
  ImageF gt_;
  Mask mask_;
};

TEST_P(RealData, WoodhamReproducesThePublishedBaselineAndPhongBeatsIt) {
  NormalOptions woodham;
  woodham.model = reflectance::Lobe::kLambert;
  woodham.discard_dark = woodham.discard_bright = 0;  // the published baseline uses every image,
  woodham.saturation = 1e30;                          // its clipped values taken as measured
  const AngularErrorMetrics w = Run(woodham);
  if (GetParam().published_woodham_deg > 0) {
    EXPECT_NEAR(w.mean_deg, GetParam().published_woodham_deg, 0.3);
  }
  // Leaving the clipped values out, as iphong's Woodham does, helps the least squares they bias
  // on the objects that have any (the ball: 4.16 -> 3.77 deg) and changes nothing elsewhere.
  NormalOptions unclipped = woodham;
  unclipped.saturation = NormalOptions{}.saturation;
  const AngularErrorMetrics u = Run(unclipped);
  RecordProperty("woodham_unclipped_mean_deg", std::to_string(u.mean_deg));
  const bool any_clipped = std::any_of(data_.values.begin(), data_.values.end(),
                                       [&](float v) { return v >= unclipped.saturation; });
  if (any_clipped) {
    EXPECT_LT(u.mean_deg, w.mean_deg);
  } else {
    EXPECT_EQ(u.mean_deg, w.mean_deg);
  }
  const AngularErrorMetrics p = Run(NormalOptions{});
  RecordProperty("woodham_mean_deg", std::to_string(w.mean_deg));
  RecordProperty("phong_mean_deg", std::to_string(p.mean_deg));
  RecordProperty("phong_median_deg", std::to_string(p.median_deg));
  std::printf("%s: Woodham %.2f deg, Phong %.2f deg (median %.2f)\n", GetParam().path, w.mean_deg,
              p.mean_deg, p.median_deg);
  EXPECT_LT(p.mean_deg, w.mean_deg - 0.5);
  if (std::string(GetParam().path) == "diligent/ball") {
    EXPECT_LE(p.mean_deg, 2.5);  // issue 4 goal
  }
}

INSTANTIATE_TEST_SUITE_P(Diligent, RealData,
                         ::testing::Values(Object{"diligent/ball", 4.10},
                                           Object{"diligent/cat", 8.41},
                                           Object{"diligent-crop8/ball", -1},
                                           Object{"diligent-crop8/cat", -1},
                                           Object{"diligent-crop8/pot1", -1}),
                         [](const auto& info) {
                           std::string name = info.param.path;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

}  // namespace
}  // namespace iphong::solve
