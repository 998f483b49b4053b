#include "geometry/mesh.h"

#include <cmath>

namespace iphong::geometry {

std::string TriangleMesh::Validate() const {
  const int n = static_cast<int>(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (!positions[i].allFinite()) return "vertex " + std::to_string(i) + " is not finite";
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      if (triangles[t][k] < 0 || triangles[t][k] >= n) {
        return "triangle " + std::to_string(t) + " refers to vertex " +
               std::to_string(triangles[t][k]) + " of " + std::to_string(n);
      }
    }
  }
  if (!corner_normals.empty() && corner_normals.size() != 3 * triangles.size()) {
    return "expected 3 corner normals per triangle";
  }
  for (std::size_t i = 0; i < corner_normals.size(); ++i) {
    if (!corner_normals[i].allFinite()) return "normal " + std::to_string(i) + " is not finite";
  }
  if (!uvs.empty() && uvs.size() != positions.size()) return "expected one uv per vertex";
  return "";
}

Vec3d FaceNormal(const TriangleMesh& mesh, std::size_t t) {
  const auto& tri = mesh.triangles[t];
  const Vec3d cross = (mesh.positions[tri[1]] - mesh.positions[tri[0]])
                          .cross(mesh.positions[tri[2]] - mesh.positions[tri[0]]);
  const double norm = cross.norm();
  return norm > 0 ? Vec3d(cross / norm) : Vec3d::Zero();
}

void ComputeFlatNormals(TriangleMesh& mesh) {
  mesh.corner_normals.resize(3 * mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Vec3d n = FaceNormal(mesh, t);
    for (int k = 0; k < 3; ++k) mesh.corner_normals[3 * t + k] = n;
  }
}

void ComputeCornerNormals(TriangleMesh& mesh, double crease_angle_deg) {
  const std::size_t tri_count = mesh.triangles.size();
  std::vector<Vec3d> face(tri_count);
  for (std::size_t t = 0; t < tri_count; ++t) face[t] = FaceNormal(mesh, t);

  // Triangles around each vertex, as a compressed adjacency list.
  std::vector<int> start(mesh.positions.size() + 1, 0);
  for (const auto& tri : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++start[tri[k] + 1];
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) start[v + 1] += start[v];
  std::vector<int> around(start.back());
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (std::size_t t = 0; t < tri_count; ++t)
    for (int k = 0; k < 3; ++k) around[fill[mesh.triangles[t][k]]++] = static_cast<int>(t);

  const double cos_crease = std::cos(crease_angle_deg * M_PI / 180.0);
  const bool smooth_all = crease_angle_deg >= 180.0;
  mesh.corner_normals.assign(3 * tri_count, Vec3d::Zero());
  for (std::size_t t = 0; t < tri_count; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[t][k];
      Vec3d sum = Vec3d::Zero();
      for (int i = start[v]; i < start[v + 1]; ++i) {
        const Vec3d& other = face[around[i]];
        if (smooth_all || other.dot(face[t]) >= cos_crease - 1e-12) sum += other;
      }
      const double norm = sum.norm();
      mesh.corner_normals[3 * t + k] = norm > 0 ? Vec3d(sum / norm) : face[t];
    }
  }
}

void TransformMesh(TriangleMesh& mesh, const Eigen::Affine3d& transform) {
  for (Vec3d& p : mesh.positions) p = transform * p;
  const Eigen::Matrix3d normal_map = transform.linear().inverse().transpose();
  for (Vec3d& n : mesh.corner_normals) n = (normal_map * n).normalized();
  // A mirroring transform flips the winding; restore counter-clockwise from outside.
  if (transform.linear().determinant() < 0) {
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
      if (!mesh.corner_normals.empty()) {
        std::swap(mesh.corner_normals[3 * t + 1], mesh.corner_normals[3 * t + 2]);
      }
    }
  }
}

void AppendMesh(TriangleMesh& mesh, const TriangleMesh& other) {
  const int offset = static_cast<int>(mesh.positions.size());
  const bool had_uvs = !mesh.uvs.empty() || mesh.positions.empty();
  mesh.positions.insert(mesh.positions.end(), other.positions.begin(), other.positions.end());
  for (const auto& tri : other.triangles) mesh.triangles.push_back(tri.array() + offset);
  mesh.corner_normals.insert(mesh.corner_normals.end(), other.corner_normals.begin(),
                             other.corner_normals.end());
  if (had_uvs && !other.uvs.empty()) {
    mesh.uvs.insert(mesh.uvs.end(), other.uvs.begin(), other.uvs.end());
  } else {
    mesh.uvs.clear();
  }
}

}  // namespace iphong::geometry
