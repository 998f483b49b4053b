// Python view of src/integrate and the height-map surfaces of src/geometry.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>

#include "arrays.h"
#include "bindings.h"
#include "geometry/height_map.h"
#include "integrate/frame_check.h"
#include "integrate/integrate.h"
#include "io/surface.h"

namespace py = pybind11;

namespace iphong::python {
namespace {

// A (H, W) float array; of the size of `like` when given.
ImageF ToScalarImage(const py::object& value, const char* what, const ImageF* like = nullptr) {
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 2 || (like && (a.shape(0) != like->height || a.shape(1) != like->width))) {
    throw std::invalid_argument(
        std::string(what) + " must have shape (H, W)" +
        (like ? " = (" + std::to_string(like->height) + ", " + std::to_string(like->width) + ")"
              : std::string()));
  }
  ImageF image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)), 1);
  std::memcpy(image.pixels.data(), a.data(), image.pixels.size() * sizeof(float));
  return image;
}

integrate::LinearSolver ParseSolver(const std::string& name) {
  if (name == "auto") return integrate::LinearSolver::kAuto;
  if (name == "cg") return integrate::LinearSolver::kConjugateGradient;
  if (name == "cholesky") return integrate::LinearSolver::kCholesky;
  throw std::invalid_argument("unknown solver '" + name + "' (auto, cg, cholesky)");
}

geometry::HeightMapFrame Frame(double pixel_size, const py::object& intrinsics) {
  geometry::HeightMapFrame frame;
  frame.pixel_size = pixel_size;
  if (!intrinsics.is_none()) {
    const std::vector<double> k = ToNumbers(intrinsics, 4, "intrinsics (fx, fy, cx, cy)");
    frame.perspective = true;
    frame.fx = k[0], frame.fy = k[1], frame.cx = k[2], frame.cy = k[3];
  }
  if (auto m = frame.Validate(); !m.empty()) throw std::invalid_argument(m);
  return frame;
}

}  // namespace

void BindIntegrate(py::module_& m) {
  m.def(
      "integrate",
      [](const py::object& normals_in, const py::object& mask_in, const std::string& method,
         const std::string& solver, double pixel_size, const py::object& intrinsics,
         const py::object& depth_prior, double prior_weight, double min_cos, bool allow_back_facing,
         double stiffness, int threads, const py::object& max_memory_gb) {
        const MemoryLimit memory = MemoryLimitFrom(max_memory_gb);
        const ImageF normals = ToImage(normals_in, "normals", memory);
        // No mask: the pixels with a normal (maps store 0 outside the object).
        const Mask mask = mask_in.is_none() ? NonZeroPixels(normals)
                                            : ToMask(mask_in, normals.width, normals.height);
        integrate::IntegrateOptions o;
        o.method = integrate::ParseMethod(method);
        o.solver = ParseSolver(solver);
        const geometry::HeightMapFrame frame = Frame(pixel_size, intrinsics);
        o.pixel_size = pixel_size;
        o.perspective = frame.perspective;
        o.intrinsics = {frame.fx, frame.fy, frame.cx, frame.cy};
        if (!depth_prior.is_none()) {
          o.depth_prior = ToScalarImage(depth_prior, "depth_prior", &normals);
        }
        o.prior_weight = prior_weight;
        o.min_cos = min_cos;
        o.allow_back_facing = allow_back_facing;
        o.stiffness = stiffness;
        o.threads = threads;
        RequireMemory(memory, io::EstimateSurfaceBytes(mask.count(), o),
                      "integrating " + std::to_string(mask.count()) + " pixels");
        integrate::IntegrateResult r;
        {
          py::gil_scoped_release release;
          r = integrate::IntegrateNormals(normals, mask, o);
        }
        const integrate::IntegrateSummary& s = r.summary;
        py::dict summary;
        summary["method"] = integrate::MethodName(s.method);
        summary["solver"] = s.solver;
        summary["pixels"] = s.pixels;
        summary["components"] = s.components;
        summary["back_facing_pixels"] = s.back_facing_pixels;
        summary["rounds"] = s.rounds;
        summary["iterations"] = s.iterations;
        summary["setup_seconds"] = s.setup_seconds;
        summary["solve_seconds"] = s.solve_seconds;
        summary["total_seconds"] = s.total_seconds;
        summary["rms_residual"] = s.rms_residual;
        summary["cut_edges"] = s.cut_edges;
        summary["separated_pixels"] = s.separated_pixels;
        summary["memory_bytes"] = s.memory_bytes;
        py::dict out;
        out["height"] = ToArray(r.height);
        out["continuity"] = ToArray(r.continuity);
        out["mask"] = ToArray(mask);
        out["summary"] = summary;
        return out;
      },
      py::arg("normals"), py::arg("mask") = py::none(), py::arg("method") = "auto",
      py::arg("solver") = "auto", py::arg("pixel_size") = 1.0, py::arg("intrinsics") = py::none(),
      py::arg("depth_prior") = py::none(), py::arg("prior_weight") = 1e-2,
      py::arg("min_cos") = 0.05, py::arg("allow_back_facing") = false, py::arg("stiffness") = 2.0,
      py::arg("threads") = 0, py::arg("max_memory_gb") = py::none(),
      R"(Heights from a normal map (H, W, 3) in the camera frame (x right, y up, z toward the viewer).

method: auto (dct on a full rectangle, else quadratic), quadratic (masked least squares), dct,
fft (Frankot-Chellappa), bilateral (keeps depth discontinuities, not creases). mask: (H, W)
bool, default the pixels with a non-zero normal. intrinsics (fx, fy, cx, cy) integrate log depth
for a perspective camera. depth_prior (H, W): known heights or depths, NaN where unknown.
Returns a dict: height (H, W) float32, NaN outside the mask (height toward the viewer in pixels x
pixel_size, or depth for a perspective camera), continuity (H, W, 2) edge weights to the right and
below (0 = cut), mask, and summary (method, solver, timings, iterations, rms_residual; for
bilateral cut_edges and separated_pixels, the pixels the cuts part from the rest of theirs).
Raises ValueError on bad input (size mismatch, empty mask, NaN, non-unit or back-facing normals)
and when the work would need more memory than max_memory_gb (default: three quarters of the
machine's).)");

  m.def(
      "height_to_mesh",
      [](const py::object& height_in, const py::object& mask_in, const py::object& normals_in,
         double pixel_size, const py::object& intrinsics) {
        const ImageF map = ToScalarImage(height_in, "height");
        const int width = map.width, height = map.height;
        const Mask mask = ToMask(mask_in, width, height);
        ImageF normals;
        geometry::HeightMeshOptions options;
        if (!normals_in.is_none()) {
          normals = ToImage(normals_in, "normals");
          if (normals.width != width || normals.height != height) {
            throw std::invalid_argument("normals must have the height map's size");
          }
          options.normals = &normals;
        }
        const geometry::TriangleMesh mesh =
            geometry::MeshFromHeightMap(map, mask, Frame(pixel_size, intrinsics), options);
        py::array_t<double> vertices(
            {static_cast<py::ssize_t>(mesh.positions.size()), py::ssize_t{3}});
        py::array_t<int> triangles(
            {static_cast<py::ssize_t>(mesh.triangles.size()), py::ssize_t{3}});
        for (std::size_t v = 0; v < mesh.positions.size(); ++v)
          for (int c = 0; c < 3; ++c) vertices.mutable_at(v, c) = mesh.positions[v][c];
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
          for (int c = 0; c < 3; ++c) triangles.mutable_at(t, c) = mesh.triangles[t][c];
        return py::make_tuple(vertices, triangles);
      },
      py::arg("height"), py::arg("mask") = py::none(), py::arg("normals") = py::none(),
      py::arg("pixel_size") = 1.0, py::arg("intrinsics") = py::none(),
      "Triangulate a height (or depth) map over its mask: (vertices (N, 3), triangles (M, 3)) in "
      "the camera frame, counter-clockwise seen from the viewer.");

  m.def(
      "normals_from_height",
      [](const py::object& height_in, const py::object& mask_in, double pixel_size,
         const py::object& intrinsics) {
        const ImageF map = ToScalarImage(height_in, "height");
        const int width = map.width, height = map.height;
        return ToArray(geometry::NormalsFromHeightMap(map, ToMask(mask_in, width, height),
                                                      Frame(pixel_size, intrinsics)));
      },
      py::arg("height"), py::arg("mask") = py::none(), py::arg("pixel_size") = 1.0,
      py::arg("intrinsics") = py::none(),
      "Unit normals (H, W, 3) of a height (or depth) map's surface by central differences; 0 "
      "where undefined.");
  m.def(
      "check_normal_frame",
      [](const py::object& normals_in, const py::object& mask_in, int threads) {
        const ImageF normals = ToImage(normals_in, "normals");
        const Mask mask = mask_in.is_none() ? NonZeroPixels(normals)
                                            : ToMask(mask_in, normals.width, normals.height);
        integrate::FrameCheckOptions options;
        options.threads = threads;
        const integrate::FrameCheckResult r = integrate::CheckNormalFrame(normals, mask, options);
        py::list readings;
        for (const integrate::FrameReadingScore& s : r.scores) {
          py::dict d;
          d["reading"] = integrate::PlaneReadingName(s.reading);
          d["silhouette_cos"] = s.silhouette_cos;
          d["consistency_deg"] = s.consistency_deg;
          readings.append(d);
        }
        py::dict out;
        out["readings"] = readings;
        out["silhouette_pixels"] = r.silhouette_pixels;
        out["better"] = integrate::PlaneReadingName(r.better);
        out["message"] = r.message;
        return out;
      },
      py::arg("normals"), py::arg("mask") = py::none(), py::arg("threads") = 0,
      "Which reading of a normal map's x and y axes (as given, y negated, x negated, swapped, "
      "turned...) makes it the normals of a surface: per reading the silhouette cosine (normals "
      "pointing out of the mask's edge: near 1 when right) and the mean angle to the surface "
      "integrated from it. `better` is 'as given' unless another reading is clearly better, with "
      "`message` saying why. A light file in another frame gives normals in that frame.");
}

}  // namespace iphong::python
