// Seed 001's vertex normals with a crease angle, primitives and transforms.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "geometry/primitives.h"

namespace iphong::geometry {
namespace {

TEST(CornerNormals, SphereNormalsApproachTheRadialDirection) {
  // (Level 1 is exactly radial by symmetry: every vertex lies on a rotation axis.)
  double previous = 1;
  for (int s : {2, 3, 5}) {
    const TriangleMesh mesh = MakeSphere(2.0, s);
    EXPECT_EQ(mesh.triangle_count(), 20u * (1u << (2 * s)));
    EXPECT_EQ(mesh.Validate(), "");
    double worst = 0;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const Vec3d radial = mesh.positions[mesh.triangles[t][k]].normalized();
        worst =
            std::max(worst, std::acos(std::min(1.0, radial.dot(mesh.corner_normals[3 * t + k]))));
        EXPECT_NEAR(mesh.positions[mesh.triangles[t][k]].norm(), 2.0, 1e-12);
      }
      EXPECT_GT(FaceNormal(mesh, t).dot(mesh.positions[mesh.triangles[t][0]]), 0)  // outward
          << "triangle " << t << " is wound clockwise";
    }
    EXPECT_LT(worst, previous);
    previous = worst;
  }
  EXPECT_LT(previous, 3e-3);  // radians, at 20 480 triangles
}

TEST(CornerNormals, CreaseAngleKeepsACubesEdgesSharp) {
  TriangleMesh box = MakeBox(Vec3d(1, 2, 3));
  ComputeCornerNormals(box, 45.0);  // 90° edges are creases
  for (std::size_t t = 0; t < box.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_TRUE(box.corner_normals[3 * t + k].isApprox(FaceNormal(box, t)));
  ComputeCornerNormals(box, 180.0);  // everything smoothed: corners point diagonally
  std::set<std::tuple<int, int, int>> octants;
  for (const Vec3d& n : box.corner_normals) {
    EXPECT_TRUE((n.array().abs() > 0.1).all()) << n.transpose();
    octants.insert({n.x() > 0, n.y() > 0, n.z() > 0});
  }
  EXPECT_EQ(octants.size(), 8u);
}

TEST(CornerNormals, SeedAverageOfUnitFaceNormals) {
  // Two triangles meeting at a 90° fold: the shared vertices get (n1 + n2)/|n1 + n2|.
  TriangleMesh mesh;
  mesh.positions = {Vec3d(0, 0, 0), Vec3d(0, 1, 0), Vec3d(1, 0, 0), Vec3d(0, 0, 1)};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}};  // normals +z and +x
  ComputeCornerNormals(mesh, 180.0);
  EXPECT_TRUE(mesh.corner_normals[0].isApprox(Vec3d(1, 0, 1).normalized()));
  EXPECT_TRUE(mesh.corner_normals[1].isApprox(Vec3d(0, 0, 1)));  // vertex 2: one face only
  ComputeCornerNormals(mesh, 60.0);
  EXPECT_TRUE(mesh.corner_normals[0].isApprox(Vec3d(0, 0, 1)));
}

TEST(Primitives, TransformMovesPositionsAndNormalsConsistently) {
  TriangleMesh mesh = MakeSphere(1.0, 2);
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.translate(Vec3d(1, 2, 3));
  t.scale(Vec3d(2, 1, 1));  // non-uniform: normals need the inverse transpose
  TransformMesh(mesh, t);
  for (std::size_t v = 0; v < mesh.triangles.size(); ++v) {
    const Vec3d p = mesh.positions[mesh.triangles[v][0]] - Vec3d(1, 2, 3);
    // Ellipsoid x²/4 + y² + z² = 1 has normal ∝ (x/4, y, z).
    const Vec3d expected = Vec3d(p.x() / 4, p.y(), p.z()).normalized();
    EXPECT_GT(mesh.corner_normals[3 * v].dot(expected), 0.995);
  }
}

TEST(Primitives, CylinderTorusPlaneAndHeightFieldAreConsistent) {
  for (const TriangleMesh& mesh :
       {MakeCylinder(0.5, 1.0, 32, true), MakeCylinder(0.5, 1.0, 32, false),
        MakeTorus(0.6, 0.2, 48, 24), MakePlane(2.0, 4), MakeBox(Vec3d(1, 1, 1)),
        MakeHeightField(BumpRipples{}, 2.0, 1.0, 40, 20)}) {
    EXPECT_EQ(mesh.Validate(), "");
    EXPECT_EQ(mesh.corner_normals.size(), 3 * mesh.triangle_count());
    for (const Vec3d& n : mesh.corner_normals) EXPECT_NEAR(n.norm(), 1.0, 1e-9);
  }
  // A plane's normals face the camera; the height field's top row is at +y.
  for (const Vec3d& n : MakePlane(2.0, 2).corner_normals) EXPECT_TRUE(n.isApprox(Vec3d(0, 0, 1)));
  const TriangleMesh hf = MakeHeightField([](double, double y) { return y; }, 2.0, 1.0, 3, 3);
  EXPECT_DOUBLE_EQ(hf.positions[0].y(), 0.5);
  EXPECT_DOUBLE_EQ(hf.positions[0].z(), 0.5);
  EXPECT_TRUE(hf.corner_normals[0].isApprox(Vec3d(0, -1, 1).normalized()));
  // The cylinder's side normals are horizontal; caps (sharp at 60°) face ±y.
  const TriangleMesh cyl = MakeCylinder(0.5, 1.0, 64, true);
  EXPECT_NEAR(cyl.corner_normals[0].y(), 0.0, 1e-12);
  EXPECT_TRUE(cyl.corner_normals[3 * (2 * 64)].isApprox(Vec3d(0, 1, 0)));
}

TEST(Primitives, BadParametersThrow) {
  EXPECT_THROW(MakeSphere(-1, 2), std::invalid_argument);
  EXPECT_THROW(MakeSphere(1, 12), std::invalid_argument);
  EXPECT_THROW(MakeTorus(0.2, 0.3, 8, 8), std::invalid_argument);
  EXPECT_THROW(MakeCylinder(1, 1, 2, false), std::invalid_argument);
  EXPECT_THROW(MakeHeightField([](double, double) { return NAN; }, 1, 1, 4, 4),
               std::invalid_argument);
}

}  // namespace
}  // namespace iphong::geometry
