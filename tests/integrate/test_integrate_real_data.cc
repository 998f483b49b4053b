// DiLiGenT ground-truth normals (../shared/data, skipped when absent) integrate to a surface
// whose own normals agree with them; the mesh written from it reads back.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "geometry/height_map.h"
#include "integrate/integrate.h"
#include "io/dataset.h"
#include "io/image_io.h"
#include "io/mesh_io.h"
#include "io/output_folder.h"
#include "io/surface.h"
#include "real_data_dir.h"
#include "solve/metrics.h"
#include "solve/normals.h"

namespace iphong::integrate {
namespace {

struct Case {
  const char* path;
  Method method;
  double bound_deg;  // mean angle between the input normals and the surface's own
};
void PrintTo(const Case& c, std::ostream* os) { *os << c.path << " " << MethodName(c.method); }

class IntegrateRealData : public ::testing::TestWithParam<Case> {};

TEST_P(IntegrateRealData, GroundTruthNormalsIntegrateToAConsistentSurface) {
  const std::string dir = test::RealDataDir() + "/" + GetParam().path;
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "no real data at " << dir;
  io::DatasetLoadOptions load;
  load.load_images = false;
  const io::Dataset d = io::LoadDataset(dir, load);
  ASSERT_GT(d.normal_gt.channels, 0) << "no ground truth in " << dir;
  // The ground truth is zero on a few mask pixels: integrate where it is defined.
  Mask mask = d.mask;
  for (std::size_t p = 0; p < mask.inside.size(); ++p) {
    const float* n = d.normal_gt.pixels.data() + 3 * p;
    if (!(n[2] > 0)) mask.inside[p] = 0;
  }
  IntegrateOptions options;
  options.method = GetParam().method;
  const IntegrateResult result = IntegrateNormals(d.normal_gt, mask, options);
  const ImageF back = geometry::NormalsFromHeightMap(result.height, mask, {});
  const solve::AngularErrorMetrics m = solve::CompareNormals(back, d.normal_gt, mask);
  std::printf(
      "%s %s: %zu px, %.3f s (%s, %lld iterations), re-differentiated normals: mean %.2f "
      "median %.2f deg\n",
      GetParam().path, MethodName(GetParam().method), result.summary.pixels,
      result.summary.total_seconds, result.summary.solver.c_str(), result.summary.iterations,
      m.mean_deg, m.median_deg);
  RecordProperty("mean_deg", std::to_string(m.mean_deg));
  EXPECT_LT(m.mean_deg, GetParam().bound_deg);
  if (GetParam().method == Method::kBilateral) {
    // Cuts where the object occludes itself, but no piece cut away: at most silhouette slivers
    // (pixels whose limb edges are cut both ways).
    std::printf("  %zu edges cut, %zu pixels separated\n", result.summary.cut_edges,
                result.summary.separated_pixels);
    EXPECT_GT(result.summary.cut_edges, 0u);
    EXPECT_LT(result.summary.separated_pixels, 0.01 * result.summary.pixels);
  }

  // The mesh of the surface goes through OpenMesh and back.
  const geometry::TriangleMesh mesh = geometry::MeshFromHeightMap(result.height, mask, {});
  const std::string path =
      testing::TempDir() + "/iphong_" +
      std::string(GetParam().path).substr(std::string(GetParam().path).rfind('/') + 1) + ".ply";
  std::filesystem::remove(path);
  io::SaveMesh(path, mesh);
  const geometry::TriangleMesh read = io::LoadMesh(path);
  EXPECT_EQ(read.positions.size(), mesh.positions.size());
  EXPECT_EQ(read.triangles.size(), mesh.triangles.size());
  std::filesystem::remove(path);
}

// The end-to-end check: the cat's recovered normals become a mesh the mesh library
// (as MeshLab and Blender would) reads back, with the files iphong writes beside it.
TEST(IntegrateRealDataCat, RecoveredNormalsBecomeAMeshThatReadsBack) {
  const std::string dir = test::RealDataDir() + "/diligent/cat";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "no real data at " << dir;
  const io::ObservationSet set = io::LoadObservations(dir);
  solve::NormalOptions options;
  options.color_residuals = false;  // the faster fit: this checks the mesh, not the normals
  const solve::NormalResult normals = solve::EstimateNormals(set.observations, options);
  Mask mask = set.dataset.mask;
  IntegrateOptions integration;
  integration.allow_back_facing = true;
  const IntegrateResult result = IntegrateNormals(normals.normals, mask, integration);
  const std::string out_dir = testing::TempDir() + "/iphong_cat_surface";
  std::filesystem::remove_all(out_dir);
  {
    io::OutputFolderOptions folder;
    folder.command = "integrate";
    io::OutputFolder out(out_dir, folder);
    io::SurfaceFileOptions files;
    files.albedo = &normals.albedo;
    const io::SurfaceFiles written = io::WriteSurfaceFiles(out, "", result, normals.normals, mask,
                                                           io::FrameOf(integration), files);
    out.Commit();
    EXPECT_LT(written.consistency_mean_deg, 5.0);
    const geometry::TriangleMesh read = io::LoadMesh(out_dir + "/mesh.ply");
    EXPECT_EQ(read.positions.size(), mask.count());
    EXPECT_EQ(read.triangles.size(), written.triangles);
    EXPECT_GT(written.triangles, 1.9 * mask.count());
    const ImageF height = io::ReadImage(out_dir + "/height.exr");
    ASSERT_EQ(height.channels, 1);
    for (std::size_t p = 0; p < mask.inside.size(); ++p) {
      ASSERT_EQ(std::isfinite(height.pixels[p]), mask.inside[p] != 0) << p;
    }
    // The picture people look at exists and has the preview's width.
    EXPECT_EQ(io::ReadImage(out_dir + "/height.png").width, 640);
  }
  std::filesystem::remove_all(out_dir);
}

INSTANTIATE_TEST_SUITE_P(Diligent, IntegrateRealData,
                         ::testing::Values(Case{"diligent/ball", Method::kQuadratic, 3.0},
                                           Case{"diligent/cat", Method::kQuadratic, 6.0},
                                           Case{"diligent/cat", Method::kBilateral, 6.0},
                                           Case{"diligent-crop8/pot1", Method::kQuadratic, 6.0}));

}  // namespace
}  // namespace iphong::integrate
