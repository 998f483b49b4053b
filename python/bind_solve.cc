// Python view of src/solve: arrays in, arrays out.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cstring>

#include "arrays.h"
#include "bindings.h"
#include "solve/metrics.h"
#include "solve/normals.h"

namespace py = pybind11;

namespace iphong::python {
void BindSolve(py::module_& m) {
  m.def(
      "estimate_normals",
      [](const py::object& images_in, const py::object& light_directions,
         const py::object& light_intensities, const py::object& mask_in, const py::object& model,
         const py::object& material, double discard_dark, double discard_bright, bool fast,
         double shadow_threshold, int threads) {
        const FloatStack images = ToImageStack(images_in);
        const std::size_t k = images.shape(0);
        const std::vector<Vec3d> intensities =
            light_intensities.is_none() ? std::vector<Vec3d>(k, Vec3d::Ones())
                                        : ToRows(light_intensities, k, "light_intensities");
        const solve::PhotometricData data =
            ToObservations(images, ToDirections(light_directions, k), intensities, mask_in);
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
            if (key != "ka" && key != "kd" && key != "ks" && key != "shininess" &&
                key != "ambient" && key != "model") {
              throw std::invalid_argument("material: unknown key '" + key +
                                          "' (ka, kd, ks, shininess, ambient, model)");
            }
          }
          auto rgb = [&](const char* key, const Vec3d& fallback) -> Vec3d {
            return d.contains(key) ? ToRgb(d[key], std::string("material['") + key + "']")
                                   : fallback;
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
        if (k < 3 && !options.known_albedo) {
          throw std::invalid_argument(
              "with 1 or 2 images pass material={'kd': ..., ...}: the coefficients must be "
              "known");
        }
        solve::NormalResult result;
        {
          py::gil_scoped_release release;
          result = solve::RecoverNormals(data, options);
        }
        py::dict out;
        out["normals"] = ToArray(result.normals);
        out["albedo"] = ToArray(result.albedo);
        out["residual"] = ToArray(result.residual);
        if (!result.specular.pixels.empty()) out["specular"] = ToArray(result.specular);
        out["model"] = reflectance::LobeName(result.model);
        out["ks"] = result.ks;
        out["shininess"] = result.shininess;
        out["ambient_term"] = result.ambient_term;
        out["material_estimated"] = result.material_estimated;
        out["specular_identifiable"] = result.specular_identifiable;
        out["specular_note"] = result.specular_note;
        py::list scores;
        for (const solve::ModelCandidate& c : result.model_choice.scored) {
          scores.append(py::dict(py::arg("model") = reflectance::LobeName(c.lobe),
                                 py::arg("shininess") = c.shininess,
                                 py::arg("heldout_cost") = c.heldout_cost));
        }
        out["model_scores"] = scores;
        if (!result.model_map.pixels.empty()) out["model_map"] = ToArray(result.model_map);
        if (!result.ambiguity_deg.pixels.empty()) {
          out["ambiguity_deg"] = ToArray(result.ambiguity_deg);
        }
        out["summary"] =
            py::dict(py::arg("message") = result.summary.message,
                     py::arg("init_seconds") = result.summary.init_seconds,
                     py::arg("model_seconds") = result.summary.model_seconds,
                     py::arg("solve_seconds") = result.summary.solve_seconds,
                     py::arg("iterations") = result.summary.iterations,
                     py::arg("pixels") = result.summary.pixels,
                     py::arg("dark_pixels") = result.summary.dark_pixels,
                     py::arg("underdetermined_pixels") = result.summary.underdetermined_pixels);
        return out;
      },
      py::arg("images"), py::arg("light_directions"), py::arg("light_intensities") = py::none(),
      py::arg("mask") = py::none(), py::arg("model") = py::none(), py::arg("material") = py::none(),
      py::arg("discard_dark") = 0.3, py::arg("discard_bright") = 0.1, py::arg("fast") = false,
      py::arg("shadow_threshold") = solve::NormalOptions{}.shadow_threshold, py::arg("threads") = 0,
      R"doc(Recover per-pixel normals and albedo (see `iphong normals`).

images (K, H, W, 3) linear float; light_directions (K, 3) from the surface toward the light;
light_intensities (K, 3) or None (ones); mask (H, W) bool or None; model None (chosen by
held-out prediction among Lambert, Phong and Blinn-Phong: model_scores lists every candidate),
"phong" or "blinn-phong" (that lobe, its shininess chosen) or "lambert" (Woodham); material: dict
with ka, ks, shininess, ambient (and model) when the coefficients are known, else ks is
estimated per pixel; shadow_threshold: observations darker than the model by more than this
fraction of the pixel's brightness count as shadowed. With the model chosen, model_map (H, W) says
per pixel which won its own held-out test: 1 the specular model, 0 Lambert, -1 no normal.
Returns normals (H, W, 3), albedo (H, W, 3), specular (H, W, 3: each pixel's ks; not for
lambert), residual (H, W; -1 where no normal was found),
the specular coefficients used or estimated, and a summary. With 1 or 2 images (material with
kd required) the global solver with smoothness, integrability and boundary priors runs instead and
the result has ambiguity_deg (H, W): the angle the data alone leaves open per pixel.)doc");

  m.def(
      "angular_error",
      [](const py::object& estimate, const py::object& ground_truth, const py::object& mask_in) {
        const ImageF e = ToImage(estimate, "estimate"), g = ToImage(ground_truth, "ground_truth");
        const solve::AngularErrorMetrics m =
            solve::CompareNormals(e, g, ToMask(mask_in, e.width, e.height));
        py::dict out;
        // The names of metrics.json and `iphong eval`.
        out["mean_angular_error_deg"] = m.mean_deg;
        out["median_angular_error_deg"] = m.median_deg;
        out["fraction_below_5_deg"] = m.below_5_deg;
        out["fraction_below_10_deg"] = m.below_10_deg;
        out["fraction_below_20_deg"] = m.below_20_deg;
        out["evaluated_pixels"] = m.pixels;
        out["error_deg"] = ToArray(m.error_deg);
        return out;
      },
      py::arg("estimate"), py::arg("ground_truth"), py::arg("mask") = py::none(),
      "Angular error statistics (degrees) and the per-pixel error map, over the mask where the "
      "ground truth is non-zero.");
}

}  // namespace iphong::python
