// The scan-line rasterizer: fill rule, incremental interpolation, z-buffer, perspective.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/primitives.h"
#include "render/rasterizer.h"

namespace iphong::render {
namespace {

using geometry::Camera;
using geometry::TriangleMesh;

// A plane tiling more than the view, interior vertices jittered so edges run at all angles.
TriangleMesh JitteredTiling(double size, int divisions, double jitter, unsigned seed) {
  TriangleMesh mesh = geometry::MakePlane(size, divisions);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  const double cell = size / divisions;
  for (Vec3d& p : mesh.positions) {
    if (std::abs(std::abs(p.x()) - size / 2) < 1e-9 || std::abs(std::abs(p.y()) - size / 2) < 1e-9)
      continue;
    p.x() += u(rng) * cell;
    p.y() += u(rng) * cell;
  }
  geometry::ComputeCornerNormals(mesh, 180);
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {  // a valid tiling: nothing folds over
    EXPECT_GT(geometry::FaceNormal(mesh, t).z(), 0.1) << "jitter folded triangle " << t;
  }
  return mesh;
}

void ExpectEveryPixelOnce(const TriangleMesh& mesh, const Camera& camera) {
  RasterOptions options;
  options.count_fragments = true;
  const GBuffer g = Rasterize({{&mesh, 0, nullptr}}, camera, options);
  int holes = 0, doubles = 0;
  for (int f : g.fragments) {
    holes += f == 0;
    doubles += f > 1;
  }
  EXPECT_EQ(holes, 0);
  EXPECT_EQ(doubles, 0);
}

TEST(Rasterizer, JitteredTilingCoversEveryPixelExactlyOnce) {
  const Camera camera = Camera::Orthographic(97, 61, 2.0);
  for (unsigned seed : {1u, 2u, 3u})
    ExpectEveryPixelOnce(JitteredTiling(2.5, 23, 0.15, seed), camera);
}

TEST(Rasterizer, VerticesOnPixelCentresCoverEveryPixelExactlyOnce) {
  // 64 px over extent 2: pixel size 1/32. A 4.0-wide plane with 128 divisions puts every vertex
  // on a pixel corner and every other diagonal through pixel centres; shifting by half a pixel
  // puts the vertices themselves on pixel centres. Both are the fill rule's hardest cases.
  const Camera camera = Camera::Orthographic(64, 64, 2.0);
  for (double shift : {0.0, 0.5 / 32}) {
    TriangleMesh mesh = geometry::MakePlane(4.0, 128);
    for (Vec3d& p : mesh.positions) p += Vec3d(shift, shift, 0);
    ExpectEveryPixelOnce(mesh, camera);
  }
}

TEST(Rasterizer, PerspectiveTilingIsWatertightToo) {
  Camera camera = Camera::Perspective(80, 60, 50, 3.0);
  TriangleMesh mesh = JitteredTiling(6.0, 31, 0.15, 9);
  Eigen::Affine3d tilt = Eigen::Affine3d::Identity();
  tilt.rotate(Eigen::AngleAxisd(0.4, Vec3d::UnitX()));
  geometry::TransformMesh(mesh, tilt);
  ExpectEveryPixelOnce(mesh, camera);
}

// Barycentric coordinates of the point where the ray through a pixel centre meets the triangle.
Vec3d RayBarycentric(const Camera& camera, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                     double col, double row) {
  Vec3d origin, dir;
  if (camera.type == geometry::CameraType::kOrthographic) {
    origin = Vec3d(camera.x_of_col(col), camera.y_of_row(row), 10);
    dir = Vec3d(0, 0, -1);
  } else {
    origin = camera.center;
    dir = Vec3d((col + 0.5 - camera.cx) / camera.fx, -(row + 0.5 - camera.cy) / camera.fy, -1);
  }
  Eigen::Matrix3d m;
  m.col(0) = b - a;
  m.col(1) = c - a;
  m.col(2) = -dir;
  const Vec3d x = m.colPivHouseholderQr().solve(origin - a);  // a + s(b−a) + t(c−a) = o + k d
  return Vec3d(1 - x[0] - x[1], x[0], x[1]);
}

void ExpectIncrementalMatchesBarycentric(const Camera& camera, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.9, 0.9), z(-0.5, 0.5);
  for (int trial = 0; trial < 20; ++trial) {
    TriangleMesh mesh;
    mesh.positions = {Vec3d(u(rng), u(rng), z(rng)), Vec3d(u(rng), u(rng), z(rng)),
                      Vec3d(u(rng), u(rng), z(rng))};
    mesh.triangles = {{0, 1, 2}};
    mesh.corner_normals = {Vec3d(1, 0, 0), Vec3d(0, 1, 0), Vec3d(0, 0, 1)};
    RasterOptions options;
    options.renormalize_normals = false;  // compare the raw linear interpolation
    const GBuffer g = Rasterize({{&mesh, 0, nullptr}}, camera, options);
    int checked = 0;
    for (int row = 0; row < g.height; ++row) {
      for (int col = 0; col < g.width; ++col) {
        const std::size_t p = static_cast<std::size_t>(row) * g.width + col;
        if (!g.covered(p)) continue;
        const Vec3d bary = RayBarycentric(camera, mesh.positions[0], mesh.positions[1],
                                          mesh.positions[2], col, row);
        EXPECT_GT(bary.minCoeff(), -1e-6) << "pixel centre outside the triangle";
        const Vec3d expected_pos =
            bary[0] * mesh.positions[0] + bary[1] * mesh.positions[1] + bary[2] * mesh.positions[2];
        for (int c = 0; c < 3; ++c) {
          ASSERT_NEAR(g.normal_cam.pixels[3 * p + c], bary[c], 1e-6);
          ASSERT_NEAR(g.Position(camera, p)[c], expected_pos[c], 1e-5);  // from float depth
        }
        ++checked;
      }
    }
    if (checked == 0) continue;
  }
}

TEST(Rasterizer, IncrementalInterpolationEqualsBarycentricOrthographic) {
  ExpectIncrementalMatchesBarycentric(Camera::Orthographic(120, 90, 2.0), 5);
}

TEST(Rasterizer, IncrementalInterpolationIsPerspectiveCorrect) {
  ExpectIncrementalMatchesBarycentric(Camera::Perspective(120, 90, 60, 2.5), 6);
}

TEST(Rasterizer, ZBufferKeepsTheNearestSurfaceWhateverTheOrder) {
  TriangleMesh back = geometry::MakePlane(1.0, 1), front = geometry::MakePlane(1.0, 1);
  for (Vec3d& p : front.positions) p += Vec3d(0.25, 0, 0.5);  // nearer the viewer (+z)
  const Camera camera = Camera::Orthographic(40, 40, 2.0);
  for (bool front_first : {false, true}) {
    std::vector<RasterItem> items = {{&back, 0, nullptr}, {&front, 1, nullptr}};
    if (front_first) std::swap(items[0], items[1]);
    const GBuffer g = Rasterize(items, camera, RasterOptions{});
    const std::size_t overlap = 20 * 40 + 22, back_only = 20 * 40 + 12;
    EXPECT_EQ(g.object_id[overlap], 1);
    EXPECT_NEAR(g.depth[overlap], -0.5, 1e-6);  // depth = −z for the main orthographic camera
    EXPECT_EQ(g.object_id[back_only], 0);
    EXPECT_EQ(g.object_id[0], -1);
  }
}

TEST(Rasterizer, SphereSilhouetteMatchesProjection) {
  const TriangleMesh sphere = geometry::MakeSphere(0.5, 5);
  const Camera ortho = Camera::Orthographic(200, 200, 2.0);
  const Camera persp = Camera::Perspective(200, 200, 40, 2.0);
  auto area = [&](const Camera& camera) {
    const GBuffer g = Rasterize({{&sphere, 0, nullptr}}, camera, RasterOptions{});
    double n = 0;
    for (int id : g.object_id) n += id >= 0;
    return n;
  };
  const double r_ortho = 0.5 / ortho.pixel_size();
  EXPECT_NEAR(area(ortho), M_PI * r_ortho * r_ortho, 0.01 * M_PI * r_ortho * r_ortho);
  // A sphere of radius r at distance d subtends a cone of half-angle asin(r/d): its image is a
  // disc of radius f·tan(asin(r/d)) = f·r/√(d² − r²).
  const double r_persp = persp.fx * 0.5 / std::sqrt(4.0 - 0.25);
  EXPECT_NEAR(area(persp), M_PI * r_persp * r_persp, 0.01 * M_PI * r_persp * r_persp);
  EXPECT_GT(r_persp, r_ortho);
}

TEST(Rasterizer, TrianglesBehindThePerspectiveEyeAreSkipped) {
  TriangleMesh mesh = geometry::MakePlane(1.0, 1);
  for (Vec3d& p : mesh.positions) p.z() = 5;  // behind a camera at z = 3
  const GBuffer g = Rasterize({{&mesh, 0, nullptr}}, Camera::Perspective(32, 32, 60, 3), {});
  for (int id : g.object_id) ASSERT_EQ(id, -1);
}

TEST(Rasterizer, RejectsInconsistentInput) {
  TriangleMesh mesh = geometry::MakePlane(1.0, 1);
  mesh.triangles[0][1] = 99;
  EXPECT_THROW(Rasterize({{&mesh, 0, nullptr}}, Camera::Orthographic(8, 8, 2), {}),
               std::invalid_argument);
  TriangleMesh ok = geometry::MakePlane(1.0, 1);
  std::vector<Vec3f> colors(1);
  EXPECT_THROW(Rasterize({{&ok, 0, &colors}}, Camera::Orthographic(8, 8, 2), {}),
               std::invalid_argument);
}

}  // namespace
}  // namespace iphong::render
