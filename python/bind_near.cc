// Python view of src/near: estimate_normals' near-light keywords, and the effective distance of
// captures with directions only.
#include <pybind11/functional.h>
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
// The effective distance's result as estimate_normals reports it.
py::dict DistanceDict(const near::EffectiveDistanceResult& r) {
  py::list candidates;
  for (const near::DistanceCandidate& c : r.scored) {
    candidates.append(py::dict(
        py::arg("distance_px") = c.distance_px, py::arg("centre_behind_px") = c.centre_behind_px,
        py::arg("test") = c.criterion, py::arg("heldout_cost") = c.heldout_cost,
        py::arg("heldout_error") = c.heldout_error));
  }
  py::list position_checks;
  for (const near::PositionCheck& c : r.position_checks) {
    position_checks.append(py::dict(py::arg("distance_px") = c.distance_px,
                                    py::arg("test") = c.criterion, py::arg("heldout_gain") = c.gain,
                                    py::arg("heldout_gain_error") = c.gain_error,
                                    py::arg("refused") = c.refused));
  }
  py::list passes;
  for (const near::NearPass& p : r.passes) {
    passes.append(py::dict(
        py::arg("light_distance_px") = p.distance, py::arg("normals_moved_deg") = p.change_deg,
        py::arg("lights_moved_deg") = p.lights_moved_deg, py::arg("seconds") = p.seconds));
  }
  return py::dict(py::arg("distance_px") = r.distance_px, py::arg("chosen") = r.chosen,
                  py::arg("object_size_px") = r.object_size_px,
                  py::arg("centre_behind_px") = r.centre_behind_px,
                  py::arg("relief_px") = r.relief_px, py::arg("test") = r.criterion,
                  py::arg("heldout_gain") = r.gain, py::arg("heldout_gain_error") = r.gain_error,
                  py::arg("model_loss_at_diffuse_distance") =
                      std::isnan(r.model_loss) ? py::object(py::none()) : py::float_(r.model_loss),
                  py::arg("model_loss_error") = std::isnan(r.model_loss_error)
                                                    ? py::object(py::none())
                                                    : py::float_(r.model_loss_error),
                  py::arg("position_checks") = position_checks, py::arg("candidates") = candidates,
                  py::arg("passes") = passes, py::arg("foil_refit") = r.foil_refit,
                  py::arg("seconds") = r.seconds);
}

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
               solve::NormalResult* result_out, solve::NormalResult* distant) {
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
      if (distant) *distant = std::move(r.distant);
      out["effective_distance"] = DistanceDict(r);
    } else {
      return false;
    }
  }
  return true;
}

namespace {

// A near pass's lights as plain arrays (float64: the same bits on a Dask worker): each point
// light's position and power (Light::Point with the inverse square), the reference directions
// and intensities (solve::SetReferenceLights), and the surface points in masked order. Distant
// lights (the foil's refit at D = ∞): no positions, powers or points.
py::dict NearLightsDict(const solve::PhotometricData& near) {
  const std::size_t k = near.point_lights.size(), n = near.points_cam.size();
  if (k == 0) {
    const std::size_t lights = near.light_directions.size();
    py::array_t<double> directions({lights, std::size_t{3}}), intensities({lights, std::size_t{3}});
    for (std::size_t j = 0; j < lights; ++j) {
      for (int c = 0; c < 3; ++c) {
        directions.mutable_at(j, c) = near.light_directions[j][c];
        intensities.mutable_at(j, c) = near.light_intensities[j][c];
      }
    }
    const auto none = [] { return py::array_t<double>(std::vector<py::ssize_t>{0, 3}); };
    return py::dict(py::arg("light_positions") = none(), py::arg("light_powers") = none(),
                    py::arg("reference_directions") = directions,
                    py::arg("reference_intensities") = intensities, py::arg("points") = none());
  }
  py::array_t<double> positions({k, std::size_t{3}}), powers({k, std::size_t{3}});
  py::array_t<double> directions({k, std::size_t{3}}), intensities({k, std::size_t{3}});
  py::array_t<double> points({n, std::size_t{3}});
  for (std::size_t j = 0; j < k; ++j) {
    const reflectance::Light& l = near.point_lights[j];
    if (l.type != reflectance::LightType::kPoint || !l.inverse_square_falloff ||
        l.specular_intensity != l.diffuse_intensity) {
      throw std::logic_error("an effective distance's lights are isotropic point lights");
    }
    for (int c = 0; c < 3; ++c) {
      positions.mutable_at(j, c) = l.position_cam[c];
      powers.mutable_at(j, c) = l.diffuse_intensity[c];
      directions.mutable_at(j, c) = near.light_directions[j][c];
      intensities.mutable_at(j, c) = near.light_intensities[j][c];
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) points.mutable_at(i, c) = near.points_cam[i][c];
  return py::dict(py::arg("light_positions") = positions, py::arg("light_powers") = powers,
                  py::arg("reference_directions") = directions,
                  py::arg("reference_intensities") = intensities, py::arg("points") = points);
}

}  // namespace

void BindNear(py::module_& m) {
  m.def(
      "effective_distance_pieces",
      [](const py::object& mask_in, const py::object& light_directions,
         const py::object& light_intensities, const py::object& plan_in,
         const py::object& distant_maps, const py::object& model, const py::object& material,
         double discard_dark, double discard_bright, bool fast, double shadow_threshold,
         std::size_t plan_sample, const py::object& light_distance,
         const std::function<py::list(const std::vector<std::vector<std::size_t>>&)>& observations,
         const std::function<py::object(const py::dict&, const py::dict&, const py::object&, bool)>&
             refine,
         int threads) {
        const solve::NormalPlan plan = PlanFrom(plan_in);
        const std::size_t k = py::len(light_directions);
        const FloatStack maps = FloatStack::ensure(distant_maps);
        if (!maps || maps.ndim() != 3 || maps.shape(2) != 11) {
          throw std::invalid_argument("distant_maps: expected (H, W, 11) as solve_normals_block");
        }
        const int h = static_cast<int>(maps.shape(0)), w = static_cast<int>(maps.shape(1));
        // Whether the blocks made a model map: a pixel chose 0 (Lambert) or 1 (the lobe).
        bool has_map = false;
        for (std::size_t p = 0; p < std::size_t(w) * h && !has_map; ++p)
          has_map = maps.data()[11 * p + 10] != -1.0f;
        solve::NormalResult distant =
            ResultFromMaps(maps, plan.options.model != reflectance::Lobe::kLambert, has_map);
        const Mask mask = ToMask(mask_in, w, h);
        solve::PhotometricData layout =
            NoObservations(w, h, light_directions, light_intensities, k);
        for (int p = 0; p < w * h; ++p)
          if (mask.inside[p]) layout.pixels.push_back(p);
        near::EffectiveDistanceOptions e;
        e.normals = OptionsFrom(model, material, discard_dark, discard_bright, fast,
                                shadow_threshold, threads);
        e.normals.plan_sample = plan_sample;
        e.normals.weigh_by_shading = plan.options.weigh_by_shading;  // as the distant plan asked
        e.distance_px = EffectiveDistanceFrom(light_distance);

        near::DistanceCapture capture;
        capture.layout = &layout;
        capture.observations = [&](const std::vector<std::vector<std::size_t>>& sets) {
          const py::list arrays = observations(sets);
          std::vector<solve::PhotometricData> out;
          for (std::size_t s = 0; s < sets.size(); ++s) {
            const FloatStack obs = FloatStack::ensure(arrays[s]);
            if (!obs || obs.ndim() != 3 || std::size_t(obs.shape(0)) != sets[s].size() ||
                std::size_t(obs.shape(1)) != k || obs.shape(2) != 3) {
              throw std::invalid_argument("observations: expected (n, K, 3) for each set");
            }
            solve::PhotometricData d = solve::SubsetObservations(layout, {});
            for (std::size_t i : sets[s]) d.pixels.push_back(layout.pixels[i]);
            d.values.assign(obs.data(), obs.data() + sets[s].size() * k * 3);
            out.push_back(std::move(d));
          }
          return out;
        };
        capture.refine = [&](const solve::PhotometricData& near_layout,
                             const solve::NormalPlan& near_plan,
                             const solve::NormalResult& previous) {
          const bool map = !previous.model_map.pixels.empty();
          const py::object refined =
              refine(NearLightsDict(near_layout), PlanDict(near_plan), MapsArray(previous), map);
          solve::NormalResult r =
              ResultFromMaps(refined, near_plan.options.model != reflectance::Lobe::kLambert, map);
          solve::SetRefinedFields(r, near_plan, previous);
          return r;
        };
        const near::EffectiveDistanceResult r =
            near::ContinueEffectiveDistance(capture, plan, std::move(distant), e);
        py::dict out = DistanceDict(r);
        if (r.foil_refit) out["maps"] = MapsArray(r.normals);
        if (std::isfinite(r.distance_px)) {
          out["maps"] = MapsArray(r.normals);
          out["model"] = reflectance::LobeName(r.normals.model);
          out["shininess"] = r.normals.shininess;
          out["ks"] = std::vector<double>{r.normals.ks[0], r.normals.ks[1], r.normals.ks[2]};
          out["ambient_term"] = std::vector<double>{
              r.normals.ambient_term[0], r.normals.ambient_term[1], r.normals.ambient_term[2]};
          out["code_offset"] = r.normals.code_offset;
          out["height"] = ToArray(r.height);
        }
        return out;
      },
      py::arg("mask"), py::arg("light_directions"), py::arg("light_intensities"), py::arg("plan"),
      py::arg("distant_maps"), py::arg("model"), py::arg("material"), py::arg("discard_dark"),
      py::arg("discard_bright"), py::arg("fast"), py::arg("shadow_threshold"),
      py::arg("plan_sample"), py::arg("light_distance"), py::arg("observations"), py::arg("refine"),
      py::arg("threads") = 0,
      R"doc(The effective light distance for iphong.dask: after the distant solve in blocks (its
maps (H, W, 11) and plan), the choice of D and the near passes as estimate_normals makes them,
the capture's observations read through observations(list of position lists) -> list of (n, K, 3)
and each pass's blocks refitted through refine(lights, plan, previous maps, model_map) -> maps.)doc");

  m.def(
      "refine_normals_block",
      [](const py::object& images_in, const py::object& mask_in, const py::object& plan_in,
         const py::dict& lights, const py::object& points_in, const py::object& previous_in,
         bool model_map, int threads) {
        solve::NormalPlan plan = PlanFrom(plan_in);
        plan.options.threads = threads;
        const FloatStack images = ToImageStack(images_in);
        const std::size_t k = images.shape(0);
        const auto rows = [&](const char* key) { return ToRows(lights[key], k, key); };
        solve::PhotometricData data = ToObservations(images, rows("reference_directions"),
                                                     rows("reference_intensities"), mask_in);
        // No light positions: distant lights (the foil's refit at D = ∞), points unused.
        if (py::len(lights["light_positions"]) > 0) {
          const std::vector<Vec3d> positions = rows("light_positions"),
                                   powers = rows("light_powers");
          for (std::size_t j = 0; j < k; ++j)
            data.point_lights.push_back(reflectance::Light::Point(positions[j], powers[j], true));
          const auto points =
              py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(points_in);
          if (!points || points.ndim() != 3 || points.shape(0) != data.height ||
              points.shape(1) != data.width || points.shape(2) != 3) {
            throw std::invalid_argument("points: expected (h, w, 3) like the block");
          }
          for (int p : data.pixels) {
            const double* x = points.data() + 3 * static_cast<std::size_t>(p);
            data.points_cam.emplace_back(x[0], x[1], x[2]);
          }
        }
        const bool specular = plan.options.model != reflectance::Lobe::kLambert;
        const solve::NormalResult previous = ResultFromMaps(previous_in, specular, model_map);
        if (previous.normals.width != data.width || previous.normals.height != data.height) {
          throw std::invalid_argument("previous: not the block's size");
        }
        solve::NormalResult r;
        {
          py::gil_scoped_release release;
          r = solve::RefineNormalsWithPlan(data, plan, previous);
        }
        return MapsArray(r);
      },
      py::arg("images"), py::arg("mask"), py::arg("plan"), py::arg("lights"), py::arg("points"),
      py::arg("previous"), py::arg("model_map"), py::arg("threads") = 1,
      R"doc(One block of a near pass of the effective distance (effective_distance_pieces' refine):
every pixel refitted from its previous maps under the pass's point lights seen from its surface
point. Returns (h, w, 11) as solve_normals_block.)doc");
}

}  // namespace iphong::python
