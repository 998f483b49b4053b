#include "geometry/height_map.h"

#include <cmath>
#include <stdexcept>

namespace iphong::geometry {

std::string HeightMapFrame::Validate() const {
  if (!ScaleInRange(pixel_size)) return "pixel size must be between 1e-12 and 1e12";
  if (perspective &&
      !(ScaleInRange(fx) && ScaleInRange(fy) && std::isfinite(cx) && std::isfinite(cy))) {
    return "intrinsics need fx, fy between 1e-12 and 1e12 and a finite principal point (cx, cy)";
  }
  return "";
}

Vec3d HeightMapPoint(const HeightMapFrame& frame, int width, int height, int col, int row,
                     double value) {
  if (!frame.perspective) {
    return Vec3d((col + 0.5 - 0.5 * width) * frame.pixel_size,
                 (0.5 * height - row - 0.5) * frame.pixel_size, value);
  }
  const double u = (col + 0.5 - frame.cx) / frame.fx, v = (row + 0.5 - frame.cy) / frame.fy;
  return Vec3d(u * value, -v * value, -value);
}

namespace {

bool Valid(const ImageF& height, const Mask& mask, int c, int r) {
  return c >= 0 && r >= 0 && c < height.width && r < height.height && mask.at(c, r) &&
         std::isfinite(*height.at(c, r));
}

}  // namespace

TriangleMesh MeshFromHeightMap(const ImageF& height, const Mask& mask, const HeightMapFrame& frame,
                               const HeightMeshOptions& options, std::vector<int>* vertex_pixel) {
  if (auto m = frame.Validate(); !m.empty()) throw std::invalid_argument(m);
  const int w = height.width, h = height.height;
  TriangleMesh mesh;
  std::vector<int> vertex(static_cast<std::size_t>(w) * h, -1);  // pixel → vertex
  std::vector<int> pixel_of;                                     // vertex → pixel
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      if (!Valid(height, mask, c, r)) continue;
      vertex[static_cast<std::size_t>(r) * w + c] = static_cast<int>(mesh.positions.size());
      mesh.positions.push_back(HeightMapPoint(frame, w, h, c, r, *height.at(c, r)));
      mesh.uvs.emplace_back((c + 0.5) / w, (r + 0.5) / h);
      pixel_of.push_back(r * w + c);
    }
  }
  // Continuity of the edge from (c, r) to the right (axis 0) or downward (axis 1).
  auto joined = [&](int c, int r, int axis) {
    return !options.continuity || options.continuity->at(c, r)[axis] >= options.cut_below;
  };
  auto add = [&](int a, int b, int d) { mesh.triangles.emplace_back(a, b, d); };
  for (int r = 0; r + 1 < h; ++r) {
    for (int c = 0; c + 1 < w; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * w + c;
      // Corners: top-left, top-right, bottom-left, bottom-right. Image rows run down while y
      // runs up, so (tl, bl, tr) is counter-clockwise seen from +z.
      const int tl = vertex[p], tr = vertex[p + 1], bl = vertex[p + w], br = vertex[p + w + 1];
      const bool top = tl >= 0 && tr >= 0 && joined(c, r, 0);
      const bool bottom = bl >= 0 && br >= 0 && joined(c, r + 1, 0);
      const bool left = tl >= 0 && bl >= 0 && joined(c, r, 1);
      const bool right = tr >= 0 && br >= 0 && joined(c + 1, r, 1);
      if (top && bottom && left && right) {
        add(tl, bl, tr);
        add(tr, bl, br);
      } else if (top && left) {
        add(tl, bl, tr);
      } else if (bottom && right) {
        add(tr, bl, br);
      } else if (top && right) {
        add(tl, br, tr);
      } else if (left && bottom) {
        add(tl, bl, br);
      }
    }
  }
  mesh.corner_normals.resize(3 * mesh.triangles.size());
  if (options.normals) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const float* n =
            options.normals->pixels.data() + 3 * std::size_t(pixel_of[mesh.triangles[t][k]]);
        mesh.corner_normals[3 * t + k] = Vec3d(n[0], n[1], n[2]);
      }
    }
  } else {
    ComputeCornerNormals(mesh, 180.0);
  }
  if (vertex_pixel) *vertex_pixel = std::move(pixel_of);
  return mesh;
}

ImageF NormalsFromHeightMap(const ImageF& height, const Mask& mask, const HeightMapFrame& frame) {
  if (auto m = frame.Validate(); !m.empty()) throw std::invalid_argument(m);
  const int w = height.width, h = height.height;
  ImageF normals(w, h, 3, 0.0f);
  auto point = [&](int c, int r) { return HeightMapPoint(frame, w, h, c, r, *height.at(c, r)); };
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      if (!Valid(height, mask, c, r)) continue;
      const bool l = Valid(height, mask, c - 1, r), rt = Valid(height, mask, c + 1, r);
      const bool u = Valid(height, mask, c, r - 1), d = Valid(height, mask, c, r + 1);
      if (!(l || rt) || !(u || d)) continue;
      const Vec3d dx = point(rt ? c + 1 : c, r) - point(l ? c - 1 : c, r);
      const Vec3d dy = point(c, u ? r - 1 : r) - point(c, d ? r + 1 : r);  // toward +y
      Vec3d n = dx.cross(dy);
      if (!(n.norm() > 0)) continue;
      n.normalize();
      float* o = normals.at(c, r);
      o[0] = static_cast<float>(n.x()), o[1] = static_cast<float>(n.y()),
      o[2] = static_cast<float>(n.z());
    }
  }
  return normals;
}

}  // namespace iphong::geometry
