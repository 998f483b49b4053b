// Triangle meshes in scene units, and their normals.
//
// Triangles are counter-clockwise seen from outside. Normals are stored per triangle corner, so a
// vertex on a sharp edge (a cube's corner) can carry one normal per side of the edge.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/types.h"

namespace iphong::geometry {

struct TriangleMesh {
  std::vector<Vec3d> positions;
  std::vector<Eigen::Vector3i> triangles;
  std::vector<Vec3d> corner_normals;  // 3 per triangle (corner k of triangle t at 3t + k)
  std::vector<Eigen::Vector2d> uvs;   // per vertex, for albedo textures; may be empty

  std::size_t triangle_count() const { return triangles.size(); }
  // Empty when consistent: indices in range, finite positions, sizes of normals/uvs match.
  std::string Validate() const;
};

// Unit normal of triangle t (zero for a degenerate triangle).
Vec3d FaceNormal(const TriangleMesh& mesh, std::size_t t);

// Seed 001's vertex normals: at each corner, the normalized sum of the unit normals of the
// triangles sharing that vertex, counting only those within `crease_angle_deg` of the corner's own
// triangle, so edges sharper than the crease angle keep their discontinuity. 180° smooths all.
void ComputeCornerNormals(TriangleMesh& mesh, double crease_angle_deg);

// Flat normals: every corner gets its triangle's normal.
void ComputeFlatNormals(TriangleMesh& mesh);

// Applies an affine map: positions by the map, normals by its inverse transpose (renormalized).
void TransformMesh(TriangleMesh& mesh, const Eigen::Affine3d& transform);

// Appends `other` (indices shifted).
void AppendMesh(TriangleMesh& mesh, const TriangleMesh& other);

}  // namespace iphong::geometry
