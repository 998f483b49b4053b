// Python view of src/calibrate: light calibration and semi-calibrated intensities.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <string>

#include "arrays.h"
#include "bindings.h"
#include "calibrate/lights.h"

namespace py = pybind11;

namespace iphong::python {
namespace {

// (K, H, W, 3) float images, as ImageF (copies: the calibrations read them whole).
std::vector<ImageF> ToImages(const py::object& value) {
  const FloatStack a = ToImageStack(value);
  const int k = int(a.shape(0)), h = int(a.shape(1)), w = int(a.shape(2));
  if (h < 1 || w < 1) throw std::invalid_argument("images: empty array");
  std::vector<ImageF> images(k, ImageF(w, h, 3));
  for (int j = 0; j < k; ++j) {
    std::copy(a.data() + std::size_t(j) * h * w * 3, a.data() + std::size_t(j + 1) * h * w * 3,
              images[j].pixels.begin());
  }
  return images;
}

py::dict HighlightDict(const calibrate::Highlight& h) {
  py::dict d;
  d["found"] = h.found;
  d["problem"] = h.problem;
  d["center_px"] = py::make_tuple(h.x_px, h.y_px);
  d["light_direction"] = h.light_dir_cam;
  d["uncertainty_deg"] = h.uncertainty_deg;
  d["uncertainty_px"] = h.uncertainty_px;
  d["spread_deg"] = h.spread_deg;
  d["pixels"] = h.pixels;
  d["saturated_pixels"] = h.saturated_pixels;
  d["highlights"] = h.blobs;
  return d;
}

py::list Notes(const std::vector<calibrate::CalibrationNote>& notes) {
  py::list out;
  for (const calibrate::CalibrationNote& n : notes) {
    std::string where = n.image < 0 ? "" : "image " + std::to_string(n.image);
    if (n.other >= 0) where += " and image " + std::to_string(n.other);
    out.append(where.empty() ? n.text : where + ": " + n.text);
  }
  return out;
}

// A matte sphere or a normal map: the shading's inverse, its results into `out`; returns the
// warnings.
py::list FromNormals(const std::vector<const ImageF*>& images, const ImageF& normals,
                     const Mask& where, bool uniform_albedo, double saturation, int threads,
                     py::dict& out) {
  calibrate::KnownNormalOptions options;
  options.saturation = saturation;
  options.uniform_albedo = uniform_albedo;
  options.threads = threads;
  calibrate::KnownNormalCalibration c;
  {
    py::gil_scoped_release release;
    c = calibrate::CalibrateFromNormals(images, normals, where, options);
  }
  if (!c.failed.empty()) {
    throw std::invalid_argument("image " + std::to_string(c.failed[0]) +
                                ": no pixel is lit where the normals say (" +
                                std::to_string(c.failed.size()) +
                                " images so): the light misses the object, or the normals are "
                                "not the object's");
  }
  out["light_directions"] = ToArray(c.light_dir_cam);
  out["light_intensities"] = ToArray(c.light_intensities);
  out["residual"] = c.residual;
  out["pixels_used"] = c.pixels_used;
  out["converged"] = c.converged;
  out["seconds"] = c.seconds;
  return Notes(c.warnings);
}

// estimate_intensities' docstring, with the library's account of what an estimate is worth.
const std::string& EstimateIntensitiesDoc() {
  static const std::string doc =
      std::string(R"doc(Each light's relative RGB intensity from images under known directions
(semi-calibrated photometric stereo; `iphong normals --estimate-intensities`). Returns
light_intensities (K, 3), each channel's mean 1, eigen_gap (how well determined: the second
smallest eigenvalue over the smallest), lambert_residual and code_offset (half a code step when
integer-coded images were better explained as truncated, the estimate made on each code's middle;
else 0); raises ValueError when the images are too far from Lambertian for the estimate (a median
relative residual over 0.05) or cannot pin it (an eigenvalue gap under 8). Accepted is not exact: )doc") +
      calibrate::kUncheckedEstimateNote +
      "; compare with measured intensities where a degree matters.";
  return doc;
}

}  // namespace

void BindCalibrate(py::module_& m) {
  m.def(
      "calibrate_lights",
      [](const py::object& images_in, const py::object& mask_in, const py::object& circles,
         const std::string& sphere, const py::object& normals_in, const py::object& intrinsics,
         double saturation, int max_spheres, bool uniform_albedo, int threads) {
        // The command line's ranges (--saturation, --spheres).
        if (!(saturation > 0 && saturation <= 1))
          throw std::invalid_argument("saturation: expected a number in (0, 1]");
        if (max_spheres < 1 || max_spheres > 2)
          throw std::invalid_argument("max_spheres: expected 1 or 2");
        const std::vector<ImageF> images = ToImages(images_in);
        std::vector<const ImageF*> pointers;
        for (const ImageF& image : images) pointers.push_back(&image);
        const int w = images[0].width, h = images[0].height;
        const Mask mask = ToMask(mask_in, w, h);
        py::dict out;
        if (!normals_in.is_none()) {
          const ImageF normals = ToImage(normals_in, "normals");
          if (normals.width != w || normals.height != h || normals.channels != 3) {
            throw std::invalid_argument("normals must have shape (H, W, 3) like the images");
          }
          out["warnings"] =
              FromNormals(pointers, normals, mask, uniform_albedo, saturation, threads, out);
          return out;
        }
        if (sphere != "mirror" && sphere != "matte") {
          throw std::invalid_argument("sphere must be 'mirror' or 'matte' (got '" + sphere + "')");
        }
        calibrate::Intrinsics camera;
        if (!intrinsics.is_none()) {
          const std::vector<double> v = ToNumbers(intrinsics, 4, "intrinsics");
          camera = {v[0], v[1], v[2], v[3]};
          if (std::string e = camera.Check(); !e.empty() || !camera.perspective()) {
            throw std::invalid_argument(
                "intrinsics: fx and fy must be between 1e-12 and 1e12, cx and cy finite");
          }
        }
        std::vector<calibrate::SphereOutline> outlines;
        std::vector<std::string> sphere_warnings;
        if (!circles.is_none()) {
          auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(circles);
          if (!a) PyErr_Clear();
          if (!a || a.ndim() != 2 || a.shape(1) != 3 || a.shape(0) < 1 || a.shape(0) > 2) {
            throw std::invalid_argument("circles must have shape (1, 3) or (2, 3): (cx, cy, r)");
          }
          const std::vector<Vec3d> rows = ToRows(circles, a.shape(0), "circles");
          for (const Vec3d& c : rows) {
            if (!(c.z() > 0)) throw std::invalid_argument("circles: a radius must be > 0");
            calibrate::SphereOutline s;
            s.center_x_px = c.x();
            s.center_y_px = c.y();
            s.radius_px = c.z();
            if (std::string m = calibrate::CheckCircle(s, w, h); !m.empty()) {
              throw std::invalid_argument("circles: " + m);
            }
            outlines.push_back(s);
          }
        } else {
          calibrate::SphereSearch search;
          search.max_spheres = max_spheres;
          outlines = mask_in.is_none()
                         ? calibrate::FindSpheresInImages(pointers, search, &sphere_warnings)
                         : calibrate::FindSpheres(mask, search, &sphere_warnings);
        }
        std::vector<calibrate::SphereGeometry> spheres;
        py::list sphere_list;
        for (const calibrate::SphereOutline& s : outlines) {
          spheres.push_back(calibrate::SphereFromOutline(s, camera));
          sphere_list.append(
              py::dict(py::arg("center_px") = py::make_tuple(s.center_x_px, s.center_y_px),
                       py::arg("radius_px") = s.radius_px, py::arg("outline_rms_px") = s.fit_rms_px,
                       py::arg("visible_fraction") = s.visible_fraction));
        }
        out["spheres"] = sphere_list;
        py::list warnings;
        for (const std::string& s : sphere_warnings) warnings.append(s);
        if (sphere == "mirror") {
          calibrate::MirrorOptions options;
          options.saturation = saturation;
          options.threads = threads;
          calibrate::MirrorCalibration c;
          {
            py::gil_scoped_release release;
            c = calibrate::CalibrateMirror(pointers, spheres, options);
          }
          if (!c.failed.empty()) {
            for (const calibrate::Highlight& hl : c.highlights[c.failed[0]])
              if (!hl.found)
                throw std::invalid_argument("image " + std::to_string(c.failed[0]) + ": " +
                                            hl.problem);
          }
          out["light_directions"] = ToArray(c.light_dir_cam);
          out["light_intensities"] = ToArray(c.light_intensities);
          out["intensities_measured"] = c.intensities_measured;
          out["light_positions"] = c.light_position_cam.empty()
                                       ? py::object(py::none())
                                       : py::object(ToArray(c.light_position_cam));
          out["positions_note"] = c.positions_note;
          py::list highlights;
          for (const auto& row : c.highlights) {
            py::list per_sphere;
            for (const calibrate::Highlight& hl : row) per_sphere.append(HighlightDict(hl));
            highlights.append(per_sphere);
          }
          out["highlights"] = highlights;
          for (const auto& w : Notes(c.warnings)) warnings.append(w);
          out["seconds"] = c.seconds;
        } else {
          Mask on_sphere;
          const ImageF normals = calibrate::SphereNormalMap(spheres, w, h, &on_sphere);
          for (const auto& n :
               FromNormals(pointers, normals, on_sphere, true, saturation, threads, out))
            warnings.append(n);
        }
        out["warnings"] = warnings;
        return out;
      },
      py::arg("images"), py::arg("mask") = py::none(), py::arg("circles") = py::none(),
      py::arg("sphere") = "mirror", py::arg("normals") = py::none(),
      py::arg("intrinsics") = py::none(), py::arg("saturation") = 1.0, py::arg("max_spheres") = 2,
      py::arg("uniform_albedo") = false, py::arg("threads") = 0,
      R"doc(Light directions (and intensities, positions) from calibration photos (see
`iphong calibrate-lights`).

images (K, H, W, 3) linear float. With normals (H, W, 3): calibrate from an object of known
normals (mask: where to use them), by robust Lambertian least squares with a per-pixel albedo
(one albedo with uniform_albedo=True: a painted target).
Otherwise a sphere, found in mask (largest regions, up to max_spheres), given as circles
[(cx, cy, r), ...] in pixels, or without either found in the photos (with a warning); sphere "mirror" (the highlights; two spheres also triangulate
point-light positions) or "matte" (the shading, one albedo). intrinsics (fx, fy, cx, cy) for a
perspective camera. Returns light_directions (K, 3), light_intensities (K, 3; each channel's mean
1, or all 1 when a mirror's highlights are clipped), warnings, and per method: spheres,
highlights [image][sphere] (center_px, uncertainty_deg, spread_deg, ...), light_positions or
None; residual and pixels_used per light. Raises ValueError when an image has no highlight.)doc");

  m.def(
      "estimate_intensities",
      [](const py::object& images_in, const py::object& light_directions, const py::object& mask_in,
         double discard_dark, double discard_bright, int threads) {
        const FloatStack images = ToImageStack(images_in);
        const std::size_t k = images.shape(0);
        const solve::PhotometricData data =
            ToObservations(images, ToDirections(light_directions, k),
                           std::vector<Vec3d>(k, Vec3d::Ones()), mask_in);
        calibrate::IntensityOptions options;
        options.discard_dark = discard_dark;
        options.discard_bright = discard_bright;
        options.threads = threads;
        calibrate::IntensityEstimate e;
        {
          py::gil_scoped_release release;
          e = calibrate::EstimateIntensities(data, options);
        }
        py::dict out;
        out["light_intensities"] = ToArray(e.light_intensities);
        out["eigen_gap"] = e.eigen_gap;
        out["lambert_residual"] = e.lambert_residual;
        out["code_offset"] = e.code_offset;
        out["seconds"] = e.seconds;
        return out;
      },
      py::arg("images"), py::arg("light_directions"), py::arg("mask") = py::none(),
      py::arg("discard_dark") = 0.3, py::arg("discard_bright") = 0.1, py::arg("threads") = 0,
      EstimateIntensitiesDoc().c_str());
}

}  // namespace iphong::python
