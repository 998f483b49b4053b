#include "io/near_capture.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "core/errors.h"
#include "io/files.h"
#include "near/near.h"

namespace iphong::io {
namespace fs = std::filesystem;
namespace {

bool IsRegularFile(const fs::path& path) {
  std::error_code e;
  return fs::is_regular_file(path, e);
}

std::string Mm(const Vec3d& v) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.4g, %.4g, %.4g) mm", v[0], v[1], v[2]);
  return text;
}

// Directions may be another length: scaled to unit, zero refused.
Vec3d Unit(const Vec3d& v, const std::string& source, int line, const char* what) {
  const double scale = v.cwiseAbs().maxCoeff();
  if (!(scale > 0)) FailInput(source, std::string("zero ") + what, line);
  return (v / scale).normalized();
}

}  // namespace

geometry::HeightMapFrame NearLightFiles::frame() const {
  geometry::HeightMapFrame f;
  f.perspective = camera.perspective;
  f.fx = camera.fx;
  f.fy = camera.fy;
  f.cx = camera.cx;
  f.cy = camera.cy;
  f.pixel_size = camera.perspective ? 1.0 : camera.pixel_size;
  return f;
}

NearLightFiles FindNearLights(const std::string& directory, std::size_t count,
                              std::vector<std::string>* warnings) {
  const fs::path dir(directory);
  NearLightFiles n;
  if (!IsRegularFile(dir / "light_positions.txt")) return n;
  n.positions_path = (dir / "light_positions.txt").string();
  n.positions_mm = ParseTriples(ReadTextFile(n.positions_path), n.positions_path, count,
                                "filenames.txt", &n.position_lines);
  // The camera frame has z toward the viewer: the object is at z < 0, and so is every light
  // that shines on its visible side from in front of the camera.
  std::size_t behind = 0;
  for (const Vec3d& s : n.positions_mm) behind += s.z() > 0;
  for (std::size_t j = 0; j < n.positions_mm.size(); ++j) {
    const Vec3d& s = n.positions_mm[j];
    if (s.z() > 0) {
      FailInput(
          n.positions_path,
          "light " + std::to_string(j + 1) + " at " + Mm(s) + " is behind the camera (z > 0" +
              (2 * behind > n.positions_mm.size()
                   ? "; " + std::to_string(behind) + " of " +
                         std::to_string(n.positions_mm.size()) +
                         " are: OpenCV's frame has y down and z into the scene, iphong's y up "
                         "and z toward the viewer — negate y and z"
                   : "") +
              "); positions are in the camera frame, the object at z < 0",
          n.position_lines[j]);
    }
  }
  n.camera_path = (dir / "camera.json").string();
  if (!IsRegularFile(n.camera_path)) {
    FailInput(
        n.positions_path,
        "a near-light capture needs camera.json beside it: {\"fx\", \"fy\", \"cx\", \"cy\"} in "
        "pixels (or {\"pixel_size\"} in mm for an orthographic camera)");
  }
  std::vector<std::string> ignored;
  n.camera = ParseCameraJson(ReadTextFile(n.camera_path), n.camera_path, &ignored);
  if (!ignored.empty() && warnings) {
    std::string keys;
    for (const std::string& k : ignored) keys += (keys.empty() ? "" : ", ") + k;
    warnings->push_back(n.camera_path + ": ignored " + keys + " (iphong reads fx, fy, cx, cy)");
  }
  if (IsRegularFile(dir / "light_axes.txt")) {
    n.axes_path = (dir / "light_axes.txt").string();
    n.axes =
        ParseTriples(ReadTextFile(n.axes_path), n.axes_path, count, "filenames.txt", &n.axis_lines);
    for (std::size_t j = 0; j < n.axes.size(); ++j) {
      n.axes[j] = Unit(n.axes[j], n.axes_path, n.axis_lines[j], "LED axis");
    }
  }
  if (IsRegularFile(dir / "light_anisotropy.txt")) {
    n.anisotropy_path = (dir / "light_anisotropy.txt").string();
    std::vector<int> lines;
    n.anisotropy = ParseScalars(ReadTextFile(n.anisotropy_path), n.anisotropy_path, count,
                                "filenames.txt", &lines);
    for (std::size_t j = 0; j < n.anisotropy.size(); ++j) {
      if (!(n.anisotropy[j] >= 0 && n.anisotropy[j] <= 1000)) {
        FailInput(n.anisotropy_path, "an LED's anisotropy mu must be in 0..1000 (0: isotropic)",
                  lines[j]);
      }
      if (n.anisotropy[j] > 0 && n.axes.empty()) {
        FailInput(
            n.anisotropy_path,
            "LEDs with an anisotropy need their axes: light_axes.txt (one unit 'ax ay az' per "
            "light, the way it points)",
            lines[j]);
      }
    }
  } else if (!n.axes.empty() && warnings) {
    warnings->push_back(n.axes_path +
                        ": LED axes without light_anisotropy.txt: the lights are taken as "
                        "isotropic (mu 0), the axes unused");
  }
  if (IsRegularFile(dir / "Depth_gt.mat")) n.depth_gt_path = (dir / "Depth_gt.mat").string();
  return n;
}

std::vector<reflectance::Light> NearPointLights(const NearLightFiles& files,
                                                const std::vector<Vec3d>& intensities) {
  std::vector<reflectance::Light> lights;
  for (std::size_t j = 0; j < files.positions_mm.size(); ++j) {
    const double mu = files.anisotropy.empty() ? 0.0 : files.anisotropy[j];
    const Vec3d axis = files.axes.empty() ? Vec3d(0, 0, -1) : files.axes[j];
    lights.push_back(reflectance::Light::Led(files.positions_mm[j], intensities.at(j), axis, mu));
  }
  return lights;
}

double LayoutDistanceMm(const NearLightFiles& files) {
  const std::vector<reflectance::Light> lights =
      NearPointLights(files, std::vector<Vec3d>(files.positions_mm.size(), Vec3d::Ones()));
  if (const double distance = near::GuessDistance(lights); distance > 0) return distance;
  std::vector<double> far;
  for (const Vec3d& s : files.positions_mm) far.push_back(s.norm());
  if (far.empty()) return 1e-3;
  std::nth_element(far.begin(), far.begin() + far.size() / 2, far.end());
  return std::max(far[far.size() / 2], 1e-3);
}

std::vector<Vec3d> DirectionsFromPositions(const NearLightFiles& files) {
  const Vec3d object(0, 0, -LayoutDistanceMm(files));
  std::vector<Vec3d> out;
  for (const Vec3d& s : files.positions_mm) {
    const Vec3d d = s - object;
    out.push_back(d.norm() > 0 ? Vec3d(d.normalized()) : Vec3d(0, 0, 1));
  }
  return out;
}

void CheckDirectionsAgree(const NearLightFiles& files, const std::vector<Vec3d>& directions,
                          const std::string& directions_path,
                          const std::vector<int>& direction_lines) {
  // The point nearest to every line S_j − t·d_j: Σ (I − d dᵀ) X = Σ (I − d dᵀ) S.
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Vec3d b = Vec3d::Zero();
  for (std::size_t j = 0; j < directions.size(); ++j) {
    const Eigen::Matrix3d p =
        Eigen::Matrix3d::Identity() - directions[j] * directions[j].transpose();
    a += p;
    b += p * files.positions_mm[j];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a);
  if (!(eig.eigenvalues()[0] > 1e-6 * eig.eigenvalues()[2])) return;  // parallel: no point
  const Vec3d x = a.ldlt().solve(b);
  const auto line_of = [&](std::size_t j) {
    return j < direction_lines.size() ? direction_lines[j] : static_cast<int>(j + 1);
  };
  for (std::size_t j = 0; j < directions.size(); ++j) {
    const Vec3d toward = files.positions_mm[j] - x;
    const double angle =
        toward.norm() > 0
            ? std::acos(std::clamp(toward.normalized().dot(directions[j]), -1.0, 1.0)) * 180 / M_PI
            : 0.0;
    if (angle > 10) {
      char text[320];
      std::snprintf(text, sizeof text,
                    "light %zu's direction is %.0f deg from the one toward its position in "
                    "light_positions.txt (seen from %s, the point nearest every light's line): "
                    "the two files describe different lights, orders or frames",
                    j + 1, angle, Mm(x).c_str());
      FailInput(directions_path, text, line_of(j));
    }
  }
  if (x.z() > 0) {
    FailInput(directions_path, "the directions point from " + Mm(x) +
                                   ", behind the camera, toward the positions: another frame?");
  }
}

}  // namespace iphong::io
