// The light file's depth axis from Woodham's unconstrained normals (solve/depth_axis.h), on an
// analytic Lambertian sphere (images written from the closed form, no renderer).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "solve/depth_axis.h"
#include "solve/photometric_data.h"

namespace iphong::solve {
namespace {

// A unit sphere filling a size² view, albedo 0.7, under a dome of `lights` directions: the
// observations, with each light's direction as the file gives it, `file(L)`.
template <typename File>
PhotometricData Sphere(int lights, File file, int size = 48) {
  std::vector<std::vector<float>> images(lights, std::vector<float>(3 * size * size, 0.0f));
  Mask mask(size, size, false);
  std::vector<Vec3d> dirs, given, intensities(lights, Vec3d::Ones());
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int j = 0; j < lights; ++j) {
    const double z = 1 - 0.6 * (j + 0.5) / lights, r = std::sqrt(1 - z * z);
    dirs.emplace_back(r * std::cos(golden * j), r * std::sin(golden * j), z);
    given.push_back(file(dirs.back()));
  }
  for (int row = 0; row < size; ++row) {
    for (int col = 0; col < size; ++col) {
      const double x = (col + 0.5) / size * 2 - 1, y = 1 - (row + 0.5) / size * 2;
      if (x * x + y * y >= 0.95) continue;
      mask.inside[row * size + col] = 1;
      const Vec3d n(x, y, std::sqrt(1 - x * x - y * y));
      for (int j = 0; j < lights; ++j) {
        const float v = static_cast<float>(0.7 * std::max(0.0, n.dot(dirs[j])));
        for (int c = 0; c < 3; ++c) images[j][3 * (row * size + col) + c] = v;
      }
    }
  }
  std::vector<const float*> pointers;
  for (const auto& image : images) pointers.push_back(image.data());
  return GatherObservations(pointers, size, size, mask, given, intensities);
}

TEST(DepthAxis, TheRightFrameFacesTheCamera) {
  const DepthAxisCheck c = CheckDepthAxis(Sphere(20, [](const Vec3d& l) { return l; }));
  EXPECT_GT(c.pixels, 1000u);
  EXPECT_LT(c.facing_away, 0.005);
  EXPECT_EQ(c.best_axis, 2);
  EXPECT_EQ(c.message, "");
}

// Lights whose file has the depth axis in its x or y: about half the normals face away, and the
// axis along which none does is named. Woodham's normals under a permuted file are the true
// ones permuted, so the share facing away is the sphere's share with that component negative.
TEST(DepthAxis, AFileWhoseXOrYIsTheDepthAxisIsNamed) {
  struct Case {
    Vec3d (*file)(const Vec3d&);
    int axis, sign;
    const char* named;
  };
  const Case cases[] = {
      {[](const Vec3d& l) { return Vec3d(l.z(), l.y(), l.x()); }, 0, 1, "lights' x as the depth"},
      {[](const Vec3d& l) { return Vec3d(l.x(), l.z(), l.y()); }, 1, 1, "lights' y as the depth"},
      // A dome described with z up and the camera looking along +y: the file's −y is the depth.
      {[](const Vec3d& l) { return Vec3d(l.x(), -l.z(), l.y()); }, 1, -1, "lights' -y as the depth"},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.named);
    const DepthAxisCheck c = CheckDepthAxis(Sphere(20, k.file));
    EXPECT_NEAR(c.facing_away, 0.5, 0.05);
    EXPECT_EQ(c.best_axis, k.axis);
    EXPECT_EQ(c.best_sign, k.sign);
    EXPECT_LT(c.best_facing, 0.005);
    EXPECT_NE(c.message.find(k.named), std::string::npos) << c.message;
    EXPECT_NE(c.message.find("Woodham's normals face away from the camera at 5"), std::string::npos)
        << c.message;
  }
}

}  // namespace
}  // namespace iphong::solve
