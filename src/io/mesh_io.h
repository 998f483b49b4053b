// Mesh files through OpenMesh: OBJ, PLY (ASCII and binary), OFF, STL in; binary PLY or OBJ out.
// Polygons are triangulated on read.
#pragma once

#include <string>
#include <vector>

#include "geometry/mesh.h"

namespace iphong::io {

struct MeshLoadOptions {
  // Normals stored in the file are used when present; otherwise (or when this is false) they are
  // computed by seed 001 with this crease angle.
  bool use_file_normals = true;
  double crease_angle_deg = 45.0;
};

// Throws std::runtime_error naming the file (missing, not a regular file, unreadable, no faces).
geometry::TriangleMesh LoadMesh(const std::string& path, const MeshLoadOptions& options = {});

// Writes per-vertex normals (the average of each vertex's corner normals) and, when given, one
// 8-bit colour per vertex (linear [0, 1] values, clamped and sRGB-encoded as viewers expect).
// PLY is written binary. Encoded in memory, then written as a new file (io/files.h's verified
// write); throws OutputError naming the file.
void SaveMesh(const std::string& path, const geometry::TriangleMesh& mesh,
              const std::vector<Vec3f>* vertex_colors = nullptr);

}  // namespace iphong::io
