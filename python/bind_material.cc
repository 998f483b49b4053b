// iphong.fit_material: src/material's FitMaterial on numpy arrays.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>

#include "arrays.h"
#include "bindings.h"
#include "material/fit.h"
#include "reflectance/material.h"
#include "render/relight.h"

namespace py = pybind11;

namespace iphong::python {
namespace {

py::object Number(double v) { return std::isfinite(v) ? py::object(py::float_(v)) : py::none(); }

py::array_t<double> Triple(const Vec3d& v) {
  return ToArray(std::vector<Vec3d>{v}).attr("reshape")(3);
}

py::dict ModelDict(const material::ModelFit& m) {
  py::dict d;
  d["model"] = reflectance::LobeName(m.lobe);
  d["ambient_term"] = Triple(m.ambient_term);
  d["ambient_term_se"] = Triple(m.ambient_se);
  d["ambient_term_robust_se"] = Triple(m.ambient_robust_se);
  d["ks"] = Triple(m.ks);
  d["ks_se"] = Triple(m.ks_se);
  d["ks_robust_se"] = Triple(m.ks_robust_se);
  d["shininess"] = m.shininess;
  d["shininess_se"] = Number(m.shininess_se);
  d["shininess_robust_se"] = Number(m.shininess_robust_se);
  d["ks_shininess_correlation"] = Triple(m.ks_shininess_correlation);
  d["kd"] = ToArray(m.kd);
  d["kd_se"] = m.kd_se.empty() ? py::object(py::none()) : py::object(ToArray(m.kd_se));
  d["sigma"] = Number(m.sigma);
  d["rss"] = m.rss;
  d["observations"] = m.observations;
  d["parameters"] = m.parameters;
  d["bic"] = Number(m.bic);
  d["heldout_rmse"] = Number(m.heldout_rmse);
  d["heldout_rmse_over_noise"] = Number(m.heldout_ratio);
  d["heldout_observations"] = m.heldout_observations;
  d["converged"] = m.converged;
  return d;
}

}  // namespace

void BindMaterial(py::module_& m) {
  m.def(
      "fit_material",
      [](const py::object& images_in, const py::object& light_directions,
         const py::object& normals_in, const py::object& light_intensities,
         const py::object& mask_in, const py::object& models, const std::string& albedo,
         const py::object& regions, int folds, int max_pixels, double saturation,
         double shadow_threshold, int threads) {
        const FloatStack images = ToImageStack(images_in);
        const std::size_t k = images.shape(0);
        const int h = static_cast<int>(images.shape(1)), w = static_cast<int>(images.shape(2));
        const std::vector<Vec3d> intensities = ToIntensities(light_intensities, k);
        const solve::PhotometricData data =
            ToObservations(images, ToDirections(light_directions, k), intensities, mask_in);
        const ImageF normal_map = ToImage(normals_in, "normals");
        if (normal_map.width != w || normal_map.height != h || normal_map.channels != 3) {
          throw std::invalid_argument("normals must have shape (H, W, 3) like the images");
        }
        material::MaterialFitOptions options;
        if (!models.is_none()) {
          options.models.clear();
          for (const py::handle& name : models) {
            options.models.push_back(reflectance::ParseLobe(ToText(name, "models")));
          }
        }
        if (albedo == "per-pixel") {
          options.albedo = material::AlbedoMode::kPerPixel;
        } else if (albedo == "uniform") {
          options.albedo = material::AlbedoMode::kUniform;
        } else if (albedo == "regions") {
          options.albedo = material::AlbedoMode::kPerRegion;
        } else {
          throw std::invalid_argument("albedo must be 'per-pixel', 'uniform' or 'regions' (got '" +
                                      albedo + "')");
        }
        if (options.albedo == material::AlbedoMode::kPerRegion) {
          // Float labels are taken when whole: a NaN cast to int is undefined (it became a
          // negative label, "left out", without a word).
          const auto exact =
              py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(regions);
          if (!exact) PyErr_Clear();
          if (exact) {
            for (py::ssize_t i = 0; i < exact.size(); ++i) {
              const double v = exact.data()[i];
              if (!std::isfinite(v) || v != std::floor(v) || std::abs(v) > 2e9) {
                throw std::invalid_argument(
                    "regions: labels must be whole numbers; the value at row " +
                    std::to_string(exact.ndim() == 2 ? i / exact.shape(1) : 0) + ", column " +
                    std::to_string(exact.ndim() == 2 ? i % exact.shape(1) : i) + " is " +
                    std::to_string(v));
              }
            }
          }
          auto labels =
              py::array_t<int, py::array::c_style | py::array::forcecast>::ensure(regions);
          if (!labels) PyErr_Clear();
          if (!labels || labels.ndim() != 2 || labels.shape(0) != h || labels.shape(1) != w) {
            throw std::invalid_argument("albedo='regions' needs regions: integer labels (H, W)");
          }
          for (int p : data.pixels) options.region.push_back(labels.data()[p]);
        } else if (!regions.is_none()) {
          throw std::invalid_argument("regions are used with albedo='regions'");
        }
        options.folds = folds;
        options.max_pixels = max_pixels;
        options.saturation = saturation;
        options.shadow_threshold = shadow_threshold;
        options.threads = threads;
        std::vector<Vec3d> normals;
        for (int p : data.pixels) {
          const float* n = normal_map.pixels.data() + 3 * std::size_t(p);
          normals.emplace_back(n[0], n[1], n[2]);
        }
        material::MaterialFit fit;
        {
          py::gil_scoped_release release;
          fit = material::FitMaterial(data, normals, options);
        }
        py::dict out;
        py::list model_list;
        for (const material::ModelFit& model : fit.models) model_list.append(ModelDict(model));
        out["models"] = model_list;
        out["chosen"] = reflectance::LobeName(fit.best().lobe);
        out["choice"] = fit.choice_note;
        out["fold"] = fit.fold;
        ImageF albedo_map(w, h, 3, NAN);
        for (std::size_t p = 0; p < data.pixel_count(); ++p)
          for (int c = 0; c < 3; ++c) {
            albedo_map.pixels[3 * std::size_t(data.pixels[p]) + c] = fit.albedo[p][c];
          }
        out["albedo"] = ToArray(albedo_map);
        py::list lobe;
        for (const material::LobeBin& b : fit.lobe) {
          py::dict bin;
          bin["angle_deg"] = b.angle_deg;
          bin["mean"] = b.mean;
          bin["standard_error"] = b.standard_error;
          bin["count"] = b.count;
          lobe.append(bin);
        }
        out["lobe"] = lobe;
        out["lobe_model"] =
            fit.lobe_model >= 0
                ? py::object(py::str(reflectance::LobeName(fit.models[fit.lobe_model].lobe)))
                : py::object(py::none());
        out["pixels"] = fit.pixels;
        out["fitted_pixels"] = fit.fitted_pixels;
        out["saturated"] = fit.saturated;
        out["censored"] = fit.censored;
        out["seconds"] = fit.summary.seconds;
        return out;
      },
      py::arg("images"), py::arg("light_directions"), py::arg("normals"),
      py::arg("light_intensities") = py::none(), py::arg("mask") = py::none(),
      py::arg("models") = py::none(), py::arg("albedo") = "per-pixel",
      py::arg("regions") = py::none(), py::arg("folds") = material::MaterialFitOptions{}.folds,
      py::arg("max_pixels") = material::MaterialFitOptions{}.max_pixels,
      py::arg("saturation") = material::MaterialFitOptions{}.saturation,
      py::arg("shadow_threshold") = material::MaterialFitOptions{}.shadow_threshold,
      py::arg("threads") = 0,
      R"doc(The material of an object of known normals (H, W, 3) from its images (K, H, W, 3)
under known lights: ka*Ia (ambient_term), kd, ks and shininess of Lambert, Phong and Blinn-Phong
(or `models`), each with standard errors (model-based, and robust: pixels as clusters) and its
held-out relighting error over interleaved folds of the lights (light j in fold j % folds); the
chosen model predicts held-out lights best (a lobe must beat Lambert by two standard errors and
1 %). albedo: 'per-pixel' (kd map), 'uniform' (one kd with standard errors) or 'regions' (one kd
per integer label in regions (H, W); labels < 0 left out). Returns models (a dict each), chosen,
choice, fold, albedo (H, W, 3; NaN where unknown), lobe (binned data of the chosen model's lobe, or
the best one's when Lambert won: lobe_model), pixels, fitted_pixels, saturated, censored, seconds.
Raises ValueError for bad input (sizes, a NaN normal, too few lights: how many are needed).)doc");

  m.def(
      "relight",
      [](const py::object& normals_in, const py::object& albedo_in, const py::object& light_in,
         const py::object& intensity, const std::string& model, const py::object& ks,
         double shininess, const py::object& ambient_term, const py::object& specular_in,
         double exposure, double specular_scale, int threads) {
        const ImageF normals = ToImage(normals_in, "normals");
        const ImageF albedo = ToImage(albedo_in, "albedo");
        ImageF specular;
        render::RelightInput input;
        input.normals_cam = &normals;
        input.albedo = &albedo;
        if (!specular_in.is_none()) {
          specular = ToImage(specular_in, "specular");
          input.specular = &specular;
        }
        input.lobe = reflectance::ParseLobe(model);
        input.ks = ToRgb(ks, "ks");
        input.shininess = shininess;
        input.ambient_term = ToRgb(ambient_term, "ambient_term");
        input.exposure = exposure;
        input.specular_scale = specular_scale;
        input.threads = threads;
        auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(light_in);
        if (!a) PyErr_Clear();
        const std::size_t lights = a && a.ndim() == 2 ? a.shape(0) : 1;
        const std::vector<Vec3d> directions = a && a.ndim() == 2
                                                  ? ToRows(light_in, lights, "light")
                                                  : std::vector<Vec3d>{ToVec3(light_in, "light")};
        const Vec3d e = ToRgb(intensity, "intensity");
        for (const Vec3d& d : directions)
          input.lights.push_back(reflectance::Light::Directional(d, e));
        // Lights given the way light travels give a black image: said, as `iphong relight` says it.
        if (const std::string note = render::LightsBehindNote(input); !note.empty()) {
          py::module_::import("warnings").attr("warn")("light: " + note);
        }
        ImageF image;
        {
          py::gil_scoped_release release;
          image = render::Relight(input);
        }
        return ToArray(image);
      },
      py::arg("normals"), py::arg("albedo"), py::arg("light"), py::arg("intensity") = 1.0,
      py::arg("model") = "lambert", py::arg("ks") = 0.0, py::arg("shininess") = 1.0,
      py::arg("ambient_term") = 0.0, py::arg("specular") = py::none(), py::arg("exposure") = 1.0,
      py::arg("specular_scale") = 1.0, py::arg("threads") = 0,
      R"doc(The captured object under new light(s) (`iphong relight`): normals (H, W, 3) and albedo
(kd, H, W, 3) as estimate_normals or fit_material return them, light a direction (3,) or several
(L, 3) toward the light, intensity one number or RGB; model 'lambert', 'phong' or 'blinn-phong'
with ks (or specular, a per-pixel ks map (H, W, 3)), shininess and ambient_term (Ia*ka). Returns
the linear image (H, W, 3) times exposure; 0 where the normal is zero or the albedo NaN.)doc");
}

}  // namespace iphong::python
