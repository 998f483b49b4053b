// The solver's options, plans and results as Python values and back, shared by the solve and
// near-light bindings (declared in bindings.h).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "arrays.h"
#include "bindings.h"
#include "solve/normals.h"

namespace py = pybind11;

namespace iphong::python {

// estimate_normals' keyword arguments as the solver's options (the same for every entry point).
solve::NormalOptions OptionsFrom(const py::object& model, const py::object& material,
                                 double discard_dark, double discard_bright, bool fast,
                                 double shadow_threshold, int threads) {
  solve::NormalOptions options;
  const bool model_given = !model.is_none();
  if (model_given) {
    options.model = reflectance::ParseLobe(ToText(model, "model"));
    options.choose_model = false;
  }
  options.discard_dark = discard_dark;
  options.discard_bright = discard_bright;
  options.threads = threads;
  options.color_residuals = !fast;
  options.shadow_threshold = shadow_threshold;
  if (!material.is_none()) {
    if (!py::isinstance<py::dict>(material)) {
      throw py::type_error(
          "material: expected a dict with ka, kd, ks, shininess, ambient, "
          "model; got " +
          TypeName(material));
    }
    const py::dict d = material.cast<py::dict>();
    for (const auto& item : d) {
      const std::string key = py::str(item.first);
      if (key != "ka" && key != "kd" && key != "ks" && key != "shininess" && key != "ambient" &&
          key != "model") {
        throw std::invalid_argument("material: unknown key '" + key +
                                    "' (ka, kd, ks, shininess, ambient, model)");
      }
    }
    auto rgb = [&](const char* key, const Vec3d& fallback) -> Vec3d {
      return d.contains(key) ? ToRgb(d[key], std::string("material['") + key + "']") : fallback;
    };
    reflectance::Material coefficients;
    coefficients.ka = rgb("ka", Vec3d::Zero());
    coefficients.kd = rgb("kd", Vec3d::Ones());
    coefficients.ks = rgb("ks", Vec3d::Zero());
    coefficients.shininess =
        d.contains("shininess") ? ToNumber(d["shininess"], "material['shininess']") : 1.0;
    if (auto m = reflectance::ValidateMaterial(coefficients); !m.empty()) {
      throw std::invalid_argument(m);
    }
    const Vec3d ambient = rgb("ambient", Vec3d::Ones());
    if ((ambient.array() < 0).any()) {
      throw std::invalid_argument("material['ambient']: must be >= 0");
    }
    options.material_known = true;
    options.ambient_term = ambient.cwiseProduct(coefficients.ka);
    options.ks = coefficients.ks;
    options.shininess = coefficients.shininess;
    if (d.contains("model") && !model_given) {
      options.model = reflectance::ParseLobe(ToText(d["model"], "material['model']"));
    }
    if (d.contains("kd")) options.known_albedo = coefficients.kd;
  }
  return options;
}

// light_intensities (K, 3), (K,) or None: all ones.
std::vector<Vec3d> Intensities(const py::object& light_intensities, std::size_t k) {
  return ToIntensities(light_intensities, k);
}

solve::PhotometricData NoObservations(int width, int height, const py::object& light_directions,
                                      const py::object& light_intensities, std::size_t k) {
  solve::PhotometricData data;
  data.width = width;
  data.height = height;
  data.images = static_cast<int>(k);
  data.light_directions = ToDirections(light_directions, k);
  data.light_intensities = Intensities(light_intensities, k);
  return data;
}

namespace {

py::dict CandidateDict(const solve::ModelCandidate& c) {
  return py::dict(
      py::arg("model") = reflectance::LobeName(c.lobe), py::arg("shininess") = c.shininess,
      py::arg("ks_prior_weight") = c.ks_prior_weight, py::arg("ks_prior") = ToList(c.ks_prior),
      py::arg("ambient_term") = ToList(c.ambient_term), py::arg("code_offset") = c.code_offset,
      py::arg("heldout_cost") = c.heldout_cost, py::arg("heldout_error") = c.heldout_error,
      py::arg("fold_angle_deg") = c.fold_angle_deg, py::arg("heldout_pixels") = c.heldout_pixels);
}

solve::ModelCandidate CandidateFrom(const py::dict& d) {
  solve::ModelCandidate c;
  c.lobe = reflectance::ParseLobe(d["model"].cast<std::string>());
  c.shininess = d["shininess"].cast<double>();
  c.ks_prior_weight = d["ks_prior_weight"].cast<double>();
  c.ks_prior = ToRgb(d["ks_prior"], "plan ks_prior");
  c.ambient_term = ToRgb(d["ambient_term"], "plan ambient_term");
  c.code_offset = d["code_offset"].cast<double>();
  c.heldout_cost = d["heldout_cost"].cast<double>();
  c.heldout_error = d["heldout_error"].cast<double>();
  c.fold_angle_deg = d["fold_angle_deg"].cast<double>();
  if (d.contains("heldout_pixels")) c.heldout_pixels = d["heldout_pixels"].cast<std::size_t>();
  return c;
}

}  // namespace

// A plan as plain Python values (floats are doubles, so a plan sent to a Dask worker and back is
// the same plan bit for bit).
py::dict PlanDict(const solve::NormalPlan& plan) {
  const solve::NormalOptions& o = plan.options;
  py::dict options(
      py::arg("model") = reflectance::LobeName(o.model), py::arg("choose_model") = o.choose_model,
      py::arg("discard_dark") = o.discard_dark, py::arg("discard_bright") = o.discard_bright,
      py::arg("saturation") = o.saturation, py::arg("shadow_threshold") = o.shadow_threshold,
      py::arg("irls_rounds") = o.irls_rounds, py::arg("search_candidates") = o.search_candidates,
      py::arg("model_sample") = o.model_sample, py::arg("plan_sample") = o.plan_sample,
      py::arg("per_pixel_model") = o.per_pixel_model,
      py::arg("color_residuals") = o.color_residuals, py::arg("max_iterations") = o.max_iterations,
      py::arg("material_known") = o.material_known,
      py::arg("ambient_term") = ToList(o.ambient_term), py::arg("code_offset") = o.code_offset,
      py::arg("ks") = ToList(o.ks), py::arg("shininess") = o.shininess,
      py::arg("known_albedo") = o.known_albedo ? py::object(ToList(*o.known_albedo)) : py::none(),
      py::arg("weigh_by_shading") = o.weigh_by_shading,
      py::arg("shading_weights") = py::dict(py::arg("upper") = o.shading_weights.upper,
                                            py::arg("weight") = o.shading_weights.weight,
                                            py::arg("offset") = o.shading_weights.offset));
  py::list scored;
  for (const solve::ModelCandidate& c : plan.model_choice.scored) scored.append(CandidateDict(c));
  return py::dict(
      py::arg("options") = options,
      py::arg("requested_model") = reflectance::LobeName(plan.requested_model),
      py::arg("chosen") = CandidateDict(plan.model_choice.chosen), py::arg("scored") = scored,
      py::arg("fold") = plan.model_choice.fold, py::arg("pixels") = plan.model_choice.pixels,
      py::arg("code_step") = plan.model_choice.code_step, py::arg("note") = plan.model_choice.note,
      py::arg("model_seconds") = plan.model_seconds);
}

solve::NormalPlan PlanFrom(const py::object& value) {
  if (!py::isinstance<py::dict>(value)) {
    throw py::type_error("plan: expected the dict plan_normals returns; got " + TypeName(value));
  }
  const py::dict d = value.cast<py::dict>();
  solve::NormalPlan plan;
  try {
    const py::dict o = d["options"].cast<py::dict>();
    solve::NormalOptions& n = plan.options;
    n.model = reflectance::ParseLobe(o["model"].cast<std::string>());
    n.choose_model = o["choose_model"].cast<bool>();
    n.discard_dark = o["discard_dark"].cast<double>();
    n.discard_bright = o["discard_bright"].cast<double>();
    n.saturation = o["saturation"].cast<double>();
    n.shadow_threshold = o["shadow_threshold"].cast<double>();
    n.irls_rounds = o["irls_rounds"].cast<int>();
    n.search_candidates = o["search_candidates"].cast<int>();
    n.model_sample = o["model_sample"].cast<int>();
    n.plan_sample = o["plan_sample"].cast<std::size_t>();
    n.per_pixel_model = o["per_pixel_model"].cast<bool>();
    n.color_residuals = o["color_residuals"].cast<bool>();
    n.max_iterations = o["max_iterations"].cast<int>();
    n.material_known = o["material_known"].cast<bool>();
    n.ambient_term = ToRgb(o["ambient_term"], "plan ambient_term");
    n.code_offset = o["code_offset"].cast<double>();
    n.ks = ToRgb(o["ks"], "plan ks");
    n.shininess = o["shininess"].cast<double>();
    if (!o["known_albedo"].is_none()) n.known_albedo = ToRgb(o["known_albedo"], "plan kd");
    n.weigh_by_shading = o["weigh_by_shading"].cast<bool>();
    const py::dict w = o["shading_weights"].cast<py::dict>();
    n.shading_weights.upper = w["upper"].cast<std::vector<double>>();
    n.shading_weights.weight = w["weight"].cast<std::vector<double>>();
    // Plans saved before offsets existed have none.
    if (w.contains("offset")) n.shading_weights.offset = w["offset"].cast<std::vector<double>>();
    plan.requested_model = reflectance::ParseLobe(d["requested_model"].cast<std::string>());
    plan.model_choice.chosen = CandidateFrom(d["chosen"].cast<py::dict>());
    for (const auto& c : d["scored"].cast<py::list>())
      plan.model_choice.scored.push_back(CandidateFrom(c.cast<py::dict>()));
    plan.model_choice.fold = d["fold"].cast<std::vector<int>>();
    plan.model_choice.pixels = d["pixels"].cast<std::size_t>();
    plan.model_choice.code_step = d["code_step"].cast<double>();
    plan.model_choice.note = d["note"].cast<std::string>();
    plan.model_seconds = d["model_seconds"].cast<double>();
  } catch (const py::error_already_set& e) {
    throw std::invalid_argument(std::string("plan: not a plan from plan_normals (") + e.what() +
                                ")");
  } catch (const py::cast_error& e) {
    throw std::invalid_argument(std::string("plan: not a plan from plan_normals (") + e.what() +
                                ")");
  }
  if (auto m = plan.options.Validate(); !m.empty()) throw std::invalid_argument("plan: " + m);
  return plan;
}

py::array_t<float> MapsArray(const solve::NormalResult& r) {
  const std::size_t h = r.normals.height, w = r.normals.width;
  py::array_t<float> out({h, w, std::size_t{11}});
  float* o = out.mutable_data();
  for (std::size_t p = 0; p < h * w; ++p) {
    float* v = o + 11 * p;
    for (int c = 0; c < 3; ++c) {
      v[c] = r.normals.pixels[3 * p + c];
      v[3 + c] = r.albedo.pixels[3 * p + c];
      v[6 + c] = r.specular.pixels.empty() ? 0.0f : r.specular.pixels[3 * p + c];
    }
    v[9] = r.residual.pixels[p];
    v[10] = r.model_map.pixels.empty() ? -1.0f : r.model_map.pixels[p];
  }
  return out;
}

solve::NormalResult ResultFromMaps(const py::object& maps_in, bool specular, bool model_map) {
  const FloatStack maps = FloatStack::ensure(maps_in);
  if (!maps || maps.ndim() != 3 || maps.shape(2) != 11) {
    throw std::invalid_argument("maps: expected (h, w, 11) float32 as solve_normals_block gives");
  }
  const int h = static_cast<int>(maps.shape(0)), w = static_cast<int>(maps.shape(1));
  solve::NormalResult r;
  r.normals = ImageF(w, h, 3);
  r.albedo = ImageF(w, h, 3);
  if (specular) r.specular = ImageF(w, h, 3);
  r.residual = ImageF(w, h, 1);
  if (model_map) r.model_map = ImageF(w, h, 1);
  const float* v = maps.data();
  for (std::size_t p = 0; p < std::size_t(h) * w; ++p, v += 11) {
    for (int c = 0; c < 3; ++c) {
      r.normals.pixels[3 * p + c] = v[c];
      r.albedo.pixels[3 * p + c] = v[3 + c];
      if (specular) r.specular.pixels[3 * p + c] = v[6 + c];
    }
    r.residual.pixels[p] = v[9];
    if (model_map) r.model_map.pixels[p] = v[10];
  }
  return r;
}

}  // namespace iphong::python
