#include "geometry/primitives.h"

#include <cmath>
#include <map>
#include <stdexcept>

namespace iphong::geometry {
namespace {

void Require(bool ok, const char* message) {
  if (!ok) throw std::invalid_argument(message);
}

int AddVertex(TriangleMesh& mesh, const Vec3d& p) {
  mesh.positions.push_back(p);
  return static_cast<int>(mesh.positions.size()) - 1;
}

}  // namespace

TriangleMesh MakeSphere(double radius, int subdivisions) {
  Require(std::isfinite(radius) && radius > 0, "sphere radius must be > 0");
  Require(subdivisions >= 0 && subdivisions <= 9, "sphere subdivisions must be in 0..9");
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh mesh;
  for (const Vec3d& p : {Vec3d(-1, t, 0), Vec3d(1, t, 0), Vec3d(-1, -t, 0), Vec3d(1, -t, 0),
                         Vec3d(0, -1, t), Vec3d(0, 1, t), Vec3d(0, -1, -t), Vec3d(0, 1, -t),
                         Vec3d(t, 0, -1), Vec3d(t, 0, 1), Vec3d(-t, 0, -1), Vec3d(-t, 0, 1)}) {
    AddVertex(mesh, p.normalized());
  }
  mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<int, int>, int> midpoints;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      const int index =
          AddVertex(mesh, (mesh.positions[a] + mesh.positions[b]).normalized().eval());
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<Eigen::Vector3i> finer;
    finer.reserve(4 * mesh.triangles.size());
    for (const auto& tri : mesh.triangles) {
      const int ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]),
                ca = midpoint(tri[2], tri[0]);
      finer.push_back({tri[0], ab, ca});
      finer.push_back({tri[1], bc, ab});
      finer.push_back({tri[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    mesh.triangles.swap(finer);
  }
  mesh.uvs.reserve(mesh.positions.size());
  for (Vec3d& p : mesh.positions) {
    mesh.uvs.emplace_back(0.5 + std::atan2(p.x(), p.z()) / (2 * M_PI),
                          std::acos(std::clamp(p.y(), -1.0, 1.0)) / M_PI);
    p *= radius;
  }
  ComputeCornerNormals(mesh, 180.0);
  return mesh;
}

TriangleMesh MakeCylinder(double radius, double height, int segments, bool capped) {
  Require(std::isfinite(radius) && radius > 0 && std::isfinite(height) && height > 0,
          "cylinder radius and height must be > 0");
  Require(segments >= 3 && segments <= 1 << 20, "cylinder segments must be >= 3");
  TriangleMesh mesh;
  const double half = 0.5 * height;
  for (int i = 0; i < segments; ++i) {
    const double a = 2 * M_PI * i / segments;
    // Angle 0 faces the camera (+z); x = r sin a so the profile runs left to right.
    AddVertex(mesh, Vec3d(radius * std::sin(a), half, radius * std::cos(a)));
    AddVertex(mesh, Vec3d(radius * std::sin(a), -half, radius * std::cos(a)));
  }
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    const int top_i = 2 * i, bottom_i = 2 * i + 1, top_j = 2 * j, bottom_j = 2 * j + 1;
    mesh.triangles.push_back({top_i, bottom_i, bottom_j});
    mesh.triangles.push_back({top_i, bottom_j, top_j});
  }
  if (capped) {
    const int top = AddVertex(mesh, Vec3d(0, half, 0));
    const int bottom = AddVertex(mesh, Vec3d(0, -half, 0));
    for (int i = 0; i < segments; ++i) {
      const int j = (i + 1) % segments;
      mesh.triangles.push_back({top, 2 * i, 2 * j});
      mesh.triangles.push_back({bottom, 2 * j + 1, 2 * i + 1});
    }
  }
  ComputeCornerNormals(mesh, 60.0);  // smooth around, sharp at the rims
  return mesh;
}

TriangleMesh MakeTorus(double ring_radius, double tube_radius, int ring_segments,
                       int tube_segments) {
  Require(std::isfinite(ring_radius) && std::isfinite(tube_radius) && tube_radius > 0 &&
              ring_radius > tube_radius,
          "torus needs ring radius > tube radius > 0");
  Require(ring_segments >= 3 && tube_segments >= 3, "torus segments must be >= 3");
  TriangleMesh mesh;
  for (int i = 0; i < ring_segments; ++i) {
    const double u = 2 * M_PI * i / ring_segments;
    for (int j = 0; j < tube_segments; ++j) {
      const double v = 2 * M_PI * j / tube_segments;
      const double r = ring_radius + tube_radius * std::cos(v);
      AddVertex(mesh, Vec3d(r * std::cos(u), r * std::sin(u), tube_radius * std::sin(v)));
      mesh.uvs.emplace_back(static_cast<double>(i) / ring_segments,
                            static_cast<double>(j) / tube_segments);
    }
  }
  auto index = [&](int i, int j) {
    return (i % ring_segments) * tube_segments + (j % tube_segments);
  };
  for (int i = 0; i < ring_segments; ++i) {
    for (int j = 0; j < tube_segments; ++j) {
      const int a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1), d = index(i, j + 1);
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({a, c, d});
    }
  }
  ComputeCornerNormals(mesh, 180.0);
  return mesh;
}

TriangleMesh MakePlane(double size, int divisions) {
  Require(std::isfinite(size) && size > 0, "plane size must be > 0");
  Require(divisions >= 1 && divisions <= 8192, "plane divisions must be in 1..8192");
  return MakeHeightField([](double, double) { return 0.0; }, size, size, divisions + 1,
                         divisions + 1);
}

TriangleMesh MakeBox(const Vec3d& size) {
  Require(size.allFinite() && (size.array() > 0).all(), "box sides must be > 0");
  TriangleMesh mesh;
  const Vec3d h = 0.5 * size;
  for (int i = 0; i < 8; ++i) {
    AddVertex(mesh, Vec3d(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z()));
  }
  // Two counter-clockwise triangles per face, seen from outside.
  mesh.triangles = {{4, 5, 7}, {4, 7, 6}, {1, 0, 2}, {1, 2, 3},   // +z, −z
                    {5, 1, 3}, {5, 3, 7}, {0, 4, 6}, {0, 6, 2},   // +x, −x
                    {6, 7, 3}, {6, 3, 2}, {0, 1, 5}, {0, 5, 4}};  // +y, −y
  ComputeFlatNormals(mesh);
  return mesh;
}

TriangleMesh MakeHeightField(const std::function<double(double, double)>& height, double size_x,
                             double size_y, int columns, int rows) {
  Require(std::isfinite(size_x) && std::isfinite(size_y) && size_x > 0 && size_y > 0,
          "height field size must be > 0");
  Require(columns >= 2 && rows >= 2, "height field needs at least 2x2 samples");
  TriangleMesh mesh;
  mesh.positions.reserve(static_cast<std::size_t>(columns) * rows);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const double u = static_cast<double>(c) / (columns - 1);
      const double v = static_cast<double>(r) / (rows - 1);
      const double x = (u - 0.5) * size_x, y = (0.5 - v) * size_y;
      const double z = height(x, y);
      Require(std::isfinite(z), "height field has a non-finite height");
      AddVertex(mesh, Vec3d(x, y, z));
      mesh.uvs.emplace_back(u, v);
    }
  }
  for (int r = 0; r + 1 < rows; ++r) {
    for (int c = 0; c + 1 < columns; ++c) {
      const int tl = r * columns + c, tr = tl + 1, bl = tl + columns, br = bl + 1;
      mesh.triangles.push_back({tl, bl, br});
      mesh.triangles.push_back({tl, br, tr});
    }
  }
  ComputeCornerNormals(mesh, 180.0);
  return mesh;
}

TriangleMesh MakeHeightField(const ImageF& heights, double size_x, double size_y) {
  Require(heights.channels >= 1, "height image needs a channel");
  const int columns = heights.width, rows = heights.height;
  return MakeHeightField(
      [&](double x, double y) {
        const int c = static_cast<int>(std::lround((x / size_x + 0.5) * (columns - 1)));
        const int r = static_cast<int>(std::lround((0.5 - y / size_y) * (rows - 1)));
        return static_cast<double>(heights.at(c, r)[0]);
      },
      size_x, size_y, columns, rows);
}

double BumpRipples::operator()(double x, double y) const {
  const double r2 = x * x + y * y;
  double z = amplitude * std::exp(-r2 / (2 * sigma * sigma));
  if (ripple_amplitude != 0)
    z += ripple_amplitude * std::sin(2 * M_PI * std::sqrt(r2) / ripple_wavelength);
  return z;
}

}  // namespace iphong::geometry
