#include "io/mesh_io.h"

#include "io/files.h"
#include "io/image_io.h"

// OpenMesh's IO header must come before the mesh kernel.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <cstdio>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/errors.h"

namespace iphong::io {
namespace fs = std::filesystem;
namespace {

struct Traits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<Traits>;

// OpenMesh narrates every write on its info log; errors still go to its error log.
void QuietOpenMeshInfoLog() { omlog().disable(); }

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// OpenMesh reserves what a header declares, so a forged 300-byte PLY that declares a billion
// vertices would end in std::bad_alloc. Headers with counts (PLY, OFF, binary STL) are checked
// against the file's size first: every element takes at least one byte per property (PLY), an
// ASCII OFF vertex at least 6 ("0 0 0\n") and a face at least 8, a binary STL facet 50.
void CheckDeclaredCounts(const std::string& path, std::uint64_t file_size) {
  std::ifstream file(path, std::ios::binary);
  std::string head(65536, '\0');
  file.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(file.gcount()));
  double needed = 0;
  std::string what;
  std::istringstream lines(head);
  std::string line;
  const std::string ext = Lower(fs::path(path).extension().string());
  if (head.rfind("ply", 0) == 0) {
    double count = 0;
    while (std::getline(lines, line) && line.rfind("end_header", 0) != 0) {
      std::istringstream words(line);
      std::string keyword, name;
      words >> keyword;
      if (keyword == "element") {
        words >> name >> count;
        if (!words || count < 0) throw std::runtime_error(path + ": bad PLY header: " + line);
        what += (what.empty() ? "" : " and ") + std::to_string(static_cast<long long>(count)) +
                " " + name;
      } else if (keyword == "property") {
        needed += count;
      }
    }
    what += " elements";
  } else if (ext == ".off") {
    std::getline(lines, line);  // "OFF" (or its variants)
    while (std::getline(lines, line) && (line.empty() || line[0] == '#')) {
    }
    std::istringstream words(line);
    double vertices = 0, faces = 0;
    if (words >> vertices >> faces && vertices >= 0 && faces >= 0) {
      needed = 6 * vertices + 8 * faces;
      what = std::to_string(static_cast<long long>(vertices)) + " vertices, " +
             std::to_string(static_cast<long long>(faces)) + " faces";
    }
  } else if (ext == ".stl" && head.rfind("solid", 0) != 0 && head.size() >= 84) {
    std::uint32_t facets = 0;
    std::memcpy(&facets, head.data() + 80, 4);
    needed = 84 + 50.0 * facets;
    what = std::to_string(facets) + " facets";
  }
  if (needed > static_cast<double>(file_size)) {
    throw std::runtime_error(path + ": declares " + what + " but has only " +
                             std::to_string(file_size) + " bytes: truncated or corrupt");
  }
}

}  // namespace

geometry::TriangleMesh LoadMesh(const std::string& path, const MeshLoadOptions& options) {
  CheckDeclaredCounts(path, RequireRegularFile(path));
  QuietOpenMeshInfoLog();
  OmMesh om;
  om.request_vertex_normals();
  om.request_vertex_texcoords2D();
  OpenMesh::IO::Options io_options;
  io_options += OpenMesh::IO::Options::VertexNormal;
  io_options += OpenMesh::IO::Options::VertexTexCoord;
  bool read = false;
  try {
    read = OpenMesh::IO::read_mesh(om, path, io_options);
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(path + ": the mesh does not fit in memory (corrupt file?)");
  }
  if (!read) {
    throw std::runtime_error(path + ": cannot read the mesh (OBJ, PLY, OFF or STL expected)");
  }
  if (om.n_faces() == 0) throw std::runtime_error(path + ": the mesh has no faces");
  geometry::TriangleMesh mesh;
  mesh.positions.reserve(om.n_vertices());
  for (const auto& v : om.vertices()) {
    const auto& p = om.point(v);
    mesh.positions.emplace_back(p[0], p[1], p[2]);
  }
  for (const auto& f : om.faces()) {
    Eigen::Vector3i tri;
    int k = 0;
    for (const auto& v : om.fv_range(f)) {
      if (k < 3) tri[k] = v.idx();
      ++k;
    }
    if (k == 3) mesh.triangles.push_back(tri);
  }
  if (io_options.check(OpenMesh::IO::Options::VertexTexCoord)) {
    for (const auto& v : om.vertices()) {
      const auto& t = om.texcoord2D(v);
      mesh.uvs.emplace_back(t[0], 1.0 - t[1]);  // files put v = 0 at the bottom
    }
  }
  if (auto m = mesh.Validate(); !m.empty()) throw std::runtime_error(path + ": " + m);
  bool file_normals =
      options.use_file_normals && io_options.check(OpenMesh::IO::Options::VertexNormal);
  if (file_normals) {
    mesh.corner_normals.reserve(3 * mesh.triangles.size());
    for (const auto& tri : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        const auto& n = om.normal(OmMesh::VertexHandle(tri[k]));
        Vec3d normal(n[0], n[1], n[2]);
        const double norm = normal.norm();
        if (!(norm > 0) || !normal.allFinite()) {
          file_normals = false;  // unusable normals in the file: compute them instead
          break;
        }
        mesh.corner_normals.push_back(normal / norm);
      }
      if (!file_normals) break;
    }
  }
  if (!file_normals) geometry::ComputeCornerNormals(mesh, options.crease_angle_deg);
  return mesh;
}

void SaveMesh(const std::string& path, const geometry::TriangleMesh& mesh,
              const std::vector<Vec3f>* vertex_colors) {
  if (auto m = mesh.Validate(); !m.empty()) throw std::runtime_error(path + ": " + m);
  if (vertex_colors && vertex_colors->size() != mesh.positions.size()) {
    throw std::runtime_error(path + ": expected one colour per vertex");
  }
  QuietOpenMeshInfoLog();
  OmMesh om;
  om.request_vertex_normals();
  if (vertex_colors) om.request_vertex_colors();
  std::vector<OmMesh::VertexHandle> handles;
  handles.reserve(mesh.positions.size());
  for (const Vec3d& p : mesh.positions) handles.push_back(om.add_vertex({p.x(), p.y(), p.z()}));
  std::vector<Vec3d> normals(mesh.positions.size(), Vec3d::Zero());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    om.add_face(handles[tri[0]], handles[tri[1]], handles[tri[2]]);
    for (int k = 0; k < 3; ++k) {
      if (!mesh.corner_normals.empty()) normals[tri[k]] += mesh.corner_normals[3 * t + k];
    }
  }
  for (std::size_t v = 0; v < normals.size(); ++v) {
    const Vec3d n = normals[v].norm() > 0 ? normals[v].normalized() : Vec3d(0, 0, 1);
    om.set_normal(handles[v], {n.x(), n.y(), n.z()});
    if (vertex_colors) {
      const Vec3f& c = (*vertex_colors)[v];
      auto byte = [](float x) {
        return static_cast<unsigned char>(std::lround(LinearToSrgb(x) * 255));
      };
      om.set_color(handles[v], {byte(c[0]), byte(c[1]), byte(c[2])});
    }
  }
  const std::string ext = fs::path(path).extension().string();
  if (vertex_colors && ext == ".obj") {
    // OpenMesh's OBJ writer has no vertex colours (it fails on the option); the common extension
    // "v x y z r g b" (MeshLab, Blender, CloudCompare, Open3D read it) is written here.
    std::string text = "# iphong: vertex colours as 'v x y z r g b' (sRGB, 0-1)\n";
    char line[160];
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      const Vec3d& p = mesh.positions[v];
      const auto c = om.color(handles[v]);
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g %.4g %.4g %.4g\n", p.x(), p.y(), p.z(),
                    c[0] / 255.0, c[1] / 255.0, c[2] / 255.0);
      text += line;
    }
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      const auto n = om.normal(handles[v]);
      std::snprintf(line, sizeof line, "vn %.6g %.6g %.6g\n", n[0], n[1], n[2]);
      text += line;
    }
    for (const auto& tri : mesh.triangles) {
      std::snprintf(line, sizeof line, "f %d//%d %d//%d %d//%d\n", tri[0] + 1, tri[0] + 1,
                    tri[1] + 1, tri[1] + 1, tri[2] + 1, tri[2] + 1);
      text += line;
    }
    WriteFileVerified(path, text);
    return;
  }
  OpenMesh::IO::Options io_options = OpenMesh::IO::Options::VertexNormal;
  if (vertex_colors) io_options += OpenMesh::IO::Options::VertexColor;
  if (ext == ".ply") io_options += OpenMesh::IO::Options::Binary;
  // Into memory first: OpenMesh reports success on a full disk; the verified write does not.
  std::ostringstream bytes(std::ios::binary);
  if (!OpenMesh::IO::write_mesh(om, bytes, ext, io_options) || bytes.str().empty()) {
    throw OutputError(path + ": cannot encode the mesh");
  }
  WriteFileVerified(path, bytes.str());
}

}  // namespace iphong::io
