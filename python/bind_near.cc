// Python view of src/near: estimate_normals' near-light keywords, and the effective distance of
// captures with directions only.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>

#include "arrays.h"
#include "bindings.h"
#include "io/near_capture.h"
#include "near/effective_distance.h"
#include "near/near.h"

namespace py = pybind11;

namespace iphong::python {
namespace {

struct NearInputs {
  std::vector<reflectance::Light> lights;
  geometry::HeightMapFrame frame;
  double distance = 0;
};

// estimate_normals' near-light keywords, checked as the near-light layout's files are.
NearInputs NearInputsFrom(const py::object& positions_in, const py::object& camera_in,
                          const py::object& axes_in, const py::object& anisotropy_in,
                          const py::object& distance_in, const solve::PhotometricData& data,
                          std::size_t k) {
  NearInputs out;
  io::NearLightFiles files;
  files.positions_mm = ToRows(positions_in, k, "light_positions");
  for (std::size_t j = 0; j < k; ++j) {
    if (files.positions_mm[j].z() > 0) {
      throw std::invalid_argument(
          "light_positions: light " + std::to_string(j + 1) +
          " is behind the camera (z > 0); positions are in the camera frame, the object at z < 0 "
          "(OpenCV's frame has y and z negated)");
    }
  }
  if (camera_in.is_none()) {
    throw std::invalid_argument(
        "camera: near lights need the camera, a dict as camera.json: {'fx', 'fy', 'cx', 'cy'} in "
        "pixels, or {'pixel_size'} in mm");
  }
  if (!py::isinstance<py::dict>(camera_in)) {
    throw py::type_error("camera: expected a dict, got " + TypeName(camera_in));
  }
  const std::string text = py::module_::import("json").attr("dumps")(camera_in).cast<std::string>();
  files.camera = io::ParseCameraJson(text, "camera");
  if (!axes_in.is_none()) {
    files.axes = ToRows(axes_in, k, "light_axes");
    for (Vec3d& a : files.axes) {
      if (!(a.norm() > 0) || !a.allFinite()) throw std::invalid_argument("light_axes: a zero axis");
      a.normalize();
    }
  }
  if (!anisotropy_in.is_none()) {
    files.anisotropy = ToNumbers(anisotropy_in, k, "light_anisotropy");
    for (double mu : files.anisotropy) {
      if (!(mu >= 0 && mu <= 1000)) {
        throw std::invalid_argument("light_anisotropy: each mu must be in 0..1000");
      }
      if (mu > 0 && files.axes.empty()) {
        throw std::invalid_argument("light_anisotropy: LEDs with an anisotropy need light_axes");
      }
    }
  }
  out.lights = io::NearPointLights(files, data.light_intensities);
  out.frame = files.frame();
  if (!distance_in.is_none()) {
    out.distance = ToNumber(distance_in, "distance");
    if (!(out.distance > 0) || !std::isfinite(out.distance)) {
      throw std::invalid_argument("distance: expected mm > 0");
    }
  }
  return out;
}

// light_distance: "auto" (0), "inf" or a number of pixels.
double EffectiveDistanceFrom(const py::object& value) {
  if (py::isinstance<py::str>(value)) {
    const std::string text = value.cast<std::string>();
    if (text == "auto") return 0;
    if (text == "inf") return std::numeric_limits<double>::infinity();
    throw std::invalid_argument("light_distance: expected 'auto', 'inf' or pixels > 0, got '" +
                                text + "'");
  }
  const double d = ToNumber(value, "light_distance");
  if (!(d > 0)) throw std::invalid_argument("light_distance: expected 'auto', 'inf' or pixels > 0");
  return d;
}

}  // namespace

bool SolveNear(const solve::PhotometricData& data, const solve::NormalOptions& options,
               const py::object& light_positions, const py::object& camera,
               const py::object& light_axes, const py::object& light_anisotropy,
               const py::object& distance, const py::object& light_distance, py::dict& out,
               solve::NormalResult* result_out) {
  const std::size_t k = static_cast<std::size_t>(data.images);
  solve::NormalResult& result = *result_out;
  if (!light_positions.is_none()) {
    // Near lights (SPEC.md): the near-light loop, as `iphong normals` runs it on the layout.
    if (k < 3) throw std::invalid_argument("near lights need at least 3 images");
    const NearInputs near =
        NearInputsFrom(light_positions, camera, light_axes, light_anisotropy, distance, data, k);
    near::NearOptions o;
    o.normals = options;
    o.distance = near.distance;
    solve::PhotometricData near_data = data;
    near_data.point_lights = near.lights;
    near::NearResult r;
    {
      py::gil_scoped_release release;
      r = near::SolveNearLights(std::move(near_data), near.frame, o);
    }
    result = r.normals;
    out["depth"] = ToArray(r.depth);
    out["points"] = ToArray(r.points);
    py::list passes;
    for (const near::NearPass& p : r.passes) {
      passes.append(py::dict(py::arg("kind") = p.kind, py::arg("normals_moved_deg") = p.change_deg,
                             py::arg("distance") = p.distance, py::arg("seconds") = p.seconds));
    }
    out["near"] = py::dict(
        py::arg("distance") = r.distance, py::arg("distance_from_images") = r.distance_from_images,
        py::arg("other_distances") = r.other_distances, py::arg("converged") = r.converged,
        py::arg("last_change_deg") = r.last_change_deg, py::arg("passes") = passes,
        py::arg("seconds") = r.seconds);
  } else {
    for (const py::object* given : {&camera, &light_axes, &light_anisotropy, &distance}) {
      if (!given->is_none()) {
        throw std::invalid_argument(
            "camera, light_axes, light_anisotropy and distance go with light_positions "
            "(near lights)");
      }
    }
    near::EffectiveDistanceOptions e;
    e.normals = options;
    e.distance_px = EffectiveDistanceFrom(light_distance);
    if (k >= 3) {
      near::EffectiveDistanceResult r;
      {
        py::gil_scoped_release release;
        r = near::SolveEffectiveDistance(data, e);
      }
      result = r.normals;
      py::list candidates;
      for (const near::DistanceCandidate& c : r.scored) {
        candidates.append(py::dict(
            py::arg("distance_px") = c.distance_px, py::arg("test") = c.criterion,
            py::arg("heldout_cost") = c.heldout_cost, py::arg("heldout_error") = c.heldout_error));
      }
      out["effective_distance"] =
          py::dict(py::arg("distance_px") = r.distance_px, py::arg("chosen") = r.chosen,
                   py::arg("object_size_px") = r.object_size_px, py::arg("test") = r.criterion,
                   py::arg("heldout_gain") = r.gain, py::arg("heldout_gain_error") = r.gain_error,
                   py::arg("model_loss_at_diffuse_distance") =
                       std::isnan(r.model_loss) ? py::object(py::none()) : py::float_(r.model_loss),
                   py::arg("model_loss_error") = std::isnan(r.model_loss_error)
                                                     ? py::object(py::none())
                                                     : py::float_(r.model_loss_error),
                   py::arg("candidates") = candidates, py::arg("seconds") = r.seconds);
    } else {
      return false;
    }
  }
  return true;
}

}  // namespace iphong::python
