// Python view of src/solve: arrays in, arrays out.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "arrays.h"
#include "bindings.h"
#include "integrate/frame_check.h"
#include "io/image_io.h"
#include "solve/depth_axis.h"
#include "solve/few_images.h"
#include "solve/image_check.h"
#include "solve/metrics.h"
#include "solve/normals.h"
#include "solve/reading_check.h"

namespace py = pybind11;

namespace iphong::python {

void BindSolve(py::module_& m) {
  m.def(
      "compare_encodings",
      [](const py::object& images_in, const py::object& light_directions,
         const py::object& light_intensities, const py::object& mask, double shadow_threshold,
         int threads) {
        const FloatStack images = ToImageStack(images_in);
        const std::size_t k = images.shape(0);
        const solve::PhotometricData data = ToObservations(
            images, ToDirections(light_directions, k), Intensities(light_intensities, k), mask);
        // The settings estimate_normals runs with (its shadow threshold, the CLI's defaults).
        solve::NormalOptions options;
        options.shadow_threshold = shadow_threshold;
        options.threads = threads;
        if (std::string m = options.Validate(); !m.empty()) throw py::value_error(m);
        solve::ReadingComparison c;
        {
          py::gil_scoped_release release;
          c = solve::CompareReadings(data, io::DecodeSrgb, solve::ReadingSettings(options));
        }
        return py::dict(
            py::arg("heldout_cost_as_given") = c.cost_as_given,
            py::arg("heldout_cost_srgb") = c.cost_reread, py::arg("loglik_gain") = c.gain,
            py::arg("loglik_gain_error") = c.gain_error, py::arg("srgb_better") = c.reread_better,
            py::arg("pixels") = c.pixels, py::arg("seconds") = c.seconds);
      },
      py::arg("images"), py::arg("light_directions"), py::arg("light_intensities") = py::none(),
      py::arg("mask") = py::none(), py::arg("shadow_threshold") = 0.1, py::arg("threads") = 0,
      R"doc(Whether images read as linear were display-encoded (`iphong normals` asks this of
files that state no colour space): a Lambertian fit with highlights censored predicts held-out
lights with the values as given and decoded by the sRGB curve, on the model choice's pixels, and
the two readings are compared as likelihoods of the same recorded values (the curve's Jacobian
included, as Box and Cox compare transforms). images (K, H, W, 3) with values in [0, 1] as read,
K >= 6; shadow_threshold as estimate_normals takes it. Returns heldout_cost_as_given and heldout_cost_srgb (mean per pixel, in units of its
censoring threshold squared), loglik_gain (per pixel, the sRGB reading's held-out log-likelihood
less the values') and its paired standard error loglik_gain_error, srgb_better (the gain beyond 3
standard errors: load them with encoding="srgb"), pixels and seconds. Raises ValueError with
fewer than 6 images.)doc");

  m.def(
      "plan_sample_indices",
      [](std::size_t masked_pixels, std::size_t plan_sample) {
        if (plan_sample < 1) throw std::invalid_argument("plan_sample must be >= 1");
        return solve::PlanSampleIndices(masked_pixels, plan_sample);
      },
      py::arg("masked_pixels"), py::arg("plan_sample") = solve::NormalOptions{}.plan_sample,
      "Positions, in the masked pixels' row-major order, of the pixels the whole-object "
      "decisions of estimate_normals see: all of them up to plan_sample, else that many at an "
      "even stride.");

  m.def(
      "plan_normals",
      [](const py::object& observations_in, const py::object& positions_in, int width, int height,
         const py::object& light_directions, const py::object& light_intensities,
         const py::object& model, const py::object& material, double discard_dark,
         double discard_bright, bool fast, double shadow_threshold, int threads,
         bool weigh_by_shading, bool per_pixel_model) {
        const FloatStack obs = FloatStack::ensure(observations_in);
        if (!obs || obs.ndim() != 3 || obs.shape(2) != 3) {
          throw std::invalid_argument("observations: expected (n, K, 3) float");
        }
        const auto positions =
            py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(
                positions_in);
        const std::size_t n = obs.shape(0), k = obs.shape(1);
        if (!positions || positions.ndim() != 1 ||
            static_cast<std::size_t>(positions.shape(0)) != n) {
          throw std::invalid_argument("positions: expected (n,) integers, one per observation row");
        }
        if (width < 1 || height < 1) throw std::invalid_argument("width and height must be >= 1");
        solve::PhotometricData data =
            NoObservations(width, height, light_directions, light_intensities, k);
        const std::int64_t* p = positions.data();
        for (std::size_t i = 0; i < n; ++i) {
          if (p[i] < 0 || p[i] >= std::int64_t{width} * height || (i > 0 && p[i] <= p[i - 1])) {
            throw std::invalid_argument("positions: must be ascending pixel indices in the image");
          }
          data.pixels.push_back(static_cast<int>(p[i]));
        }
        data.values.assign(obs.data(), obs.data() + n * k * 3);
        for (float v : data.values)
          if (!std::isfinite(v)) throw std::invalid_argument("observations: a non-finite value");
        solve::NormalOptions options = OptionsFrom(model, material, discard_dark, discard_bright,
                                                   fast, shadow_threshold, threads);
        options.weigh_by_shading = weigh_by_shading;
        options.per_pixel_model = per_pixel_model;
        if (k < 3) throw std::invalid_argument("the plan needs at least 3 images");
        solve::NormalPlan plan;
        {
          py::gil_scoped_release release;
          plan = solve::PlanNormals(data, options);
        }
        return PlanDict(plan);
      },
      py::arg("observations"), py::arg("positions"), py::arg("width"), py::arg("height"),
      py::arg("light_directions"), py::arg("light_intensities") = py::none(),
      py::arg("model") = py::none(), py::arg("material") = py::none(),
      py::arg("discard_dark") = 0.3, py::arg("discard_bright") = 0.1, py::arg("fast") = false,
      py::arg("shadow_threshold") = solve::NormalOptions{}.shadow_threshold, py::arg("threads") = 0,
      py::kw_only(), py::arg("weigh_by_shading") = solve::NormalOptions{}.weigh_by_shading,
      py::arg("per_pixel_model") = solve::NormalOptions{}.per_pixel_model,
      R"doc(The whole-object decisions of estimate_normals (the model, its shininess, the ambient
term, the weights and offsets by N·L), from the plan sample: observations (n, K, 3) of the
pixels at `positions` (ascending row-major indices in a width x height image;
plan_sample_indices says which). Returns a plan, a
dict of plain values for solve_normals_block. Arguments as estimate_normals.)doc");

  m.def(
      "solve_normals_block",
      [](const py::object& images_in, const py::object& mask_in, const py::object& light_directions,
         const py::object& light_intensities, const py::object& plan_in, int threads) {
        solve::NormalPlan plan = PlanFrom(plan_in);
        plan.options.threads = threads;
        const FloatStack images = ToImageStack(images_in);
        const std::size_t k = images.shape(0);
        const solve::PhotometricData data = ToObservations(
            images, ToDirections(light_directions, k), Intensities(light_intensities, k), mask_in);
        if (k < 3) throw std::invalid_argument("a block needs at least 3 images");
        solve::NormalResult r;
        {
          py::gil_scoped_release release;
          r = solve::SolveNormalsWithPlan(data, plan);
        }
        return MapsArray(r);
      },
      py::arg("images"), py::arg("mask"), py::arg("light_directions"),
      py::arg("light_intensities") = py::none(), py::arg("plan"), py::arg("threads") = 1,
      R"doc(Every pixel of one block (images (K, h, w, 3), mask (h, w) or None) fitted with a plan
from plan_normals: (h, w, 11) float32 = normals 0:3, albedo 3:6, specular 6:9 (0 without a lobe),
residual 9 (-1: no normal), model map 10 (1 specular, 0 Lambert, -1 none). A pixel's values
depend on its own observations and the plan only, so any blocking gives the same maps.)doc");

  m.def(
      "estimate_normals",
      [](const py::object& images_in, const py::object& light_directions,
         const py::object& light_intensities, const py::object& mask_in, const py::object& model,
         const py::object& material, double discard_dark, double discard_bright, bool fast,
         double shadow_threshold, int threads, const py::object& max_memory_gb,
         const py::object& light_positions, const py::object& camera, const py::object& light_axes,
         const py::object& light_anisotropy, const py::object& distance,
         const py::object& light_distance, bool weigh_by_shading, bool per_pixel_model) {
        const MemoryLimit memory = MemoryLimitFrom(max_memory_gb);
        const FloatStack images = ToImageStack(images_in);
        const std::size_t k = images.shape(0);
        const solve::PhotometricData data = ToObservations(
            images, ToDirections(light_directions, k), Intensities(light_intensities, k), mask_in);
        solve::NormalOptions options = OptionsFrom(model, material, discard_dark, discard_bright,
                                                   fast, shadow_threshold, threads);
        options.weigh_by_shading = weigh_by_shading;
        options.per_pixel_model = per_pixel_model;
        if (k < 3 && !options.known_albedo) {
          throw std::invalid_argument(
              "with 1 or 2 images pass material={'kd': ..., ...}: the coefficients must be "
              "known");
        }
        // The one- and two-image solve needs kFewImageBytesPerPixel a masked pixel: refused
        // before it starts rather than let it outgrow the machine.
        if (k < 3) {
          RequireMemory(
              memory, data.pixels.size() * solve::kFewImageBytesPerPixel,
              "the one- and two-image solve of " + std::to_string(data.pixels.size()) + " pixels");
        }
        py::dict out;
        // The light array's frame, as `iphong normals` checks a light file (both look at what
        // the photos say): its depth axis first, from Woodham's unconstrained normals; the image
        // plane's readings then from the normals recovered. Not for near lights, nor for lights
        // mostly behind the object (the fix is not a reading), nor one or two images.
        const bool check_frame =
            light_positions.is_none() && k >= 3 && !solve::MostLightsBehind(data.light_directions);
        const auto warn = [](const std::string& what) {
          py::module_::import("warnings")
              .attr("warn")("light_directions look like another frame: " + what +
                            "; check their axes (x right, y up toward row 0, z toward the camera)");
        };
        bool depth_slip = false;
        if (check_frame) {
          const solve::DepthAxisCheck c = solve::CheckDepthAxis(data);
          out["depth_axis_check"] = py::dict(
              py::arg("pixels") = c.pixels, py::arg("facing_away") = c.facing_away,
              py::arg("best_axis") = c.BestAxisName(), py::arg("best_facing_away") = c.best_facing);
          depth_slip = !c.message.empty();
          if (depth_slip) warn(c.message);
        }
        solve::NormalResult result, distant;
        bool solved_distant = false;
        if (!SolveNear(data, options, light_positions, camera, light_axes, light_anisotropy,
                       distance, light_distance, out, &result, &distant)) {
          py::gil_scoped_release release;
          result = solve::RecoverNormals(data, options);
        } else {
          solved_distant = light_positions.is_none();
        }
        // Which images disagree with the others, as `iphong normals` says it: against the
        // distant solve (solve/image_check.h). Not for near lights nor one or two images.
        if (light_positions.is_none() && k >= 3) {
          solve::ImageCheckOptions image_options;
          image_options.saturation = options.saturation;
          image_options.shadow_threshold = options.shadow_threshold;
          if (options.material_known) image_options.known_ks = options.ks;
          image_options.threads = threads;
          const solve::ImageCheck c =
              solve::CheckImages(data, solved_distant ? distant : result, image_options);
          if (c.checked) {
            out["image_check"] =
                py::dict(py::arg("misfit") = c.misfit, py::arg("score") = c.score,
                         py::arg("observations") = c.observations,
                         py::arg("typical_misfit") = c.typical_misfit,
                         py::arg("disagreeing") = c.disagreeing, py::arg("heldout") = c.heldout);
            if (!c.disagreeing.empty()) {
              std::string which;
              for (const int j : c.disagreeing) {
                which += (which.empty() ? "" : ", ") + std::to_string(j);
              }
              py::module_::import("warnings")
                  .attr("warn")(
                      (c.disagreeing.size() == 1 ? "image " : "images ") + which +
                      (c.disagreeing.size() == 1 ? " (0-based) disagrees" : " (0-based) disagree") +
                      " with the others: check those lights' directions and "
                      "intensities, the images' order, and whether the object or "
                      "camera moved");
            }
          }
        }
        if (check_frame && !depth_slip && result.ambiguity_deg.pixels.empty()) {
          // The mask's pixels with a normal: its edge is the silhouette the check reads.
          Mask solved(result.residual.width, result.residual.height, false);
          for (const auto p : data.pixels) solved.inside[p] = result.residual.pixels[p] >= 0;
          integrate::FrameCheckOptions frame;
          frame.threads = threads;
          const integrate::FrameCheckResult f =
              integrate::CheckNormalFrame(result.normals, solved, frame);
          out["frame_check"] = integrate::PlaneReadingName(f.better);
          if (!f.message.empty()) warn(f.message);
        }
        out["normals"] = ToArray(result.normals);
        out["albedo"] = ToArray(result.albedo);
        out["residual"] = ToArray(result.residual);
        if (!result.specular.pixels.empty()) out["specular"] = ToArray(result.specular);
        out["model"] = reflectance::LobeName(result.model);
        out["ks"] = result.ks;
        out["shininess"] = result.shininess;
        out["ambient_term"] = result.ambient_term;
        out["code_offset"] = result.code_offset;
        out["material_estimated"] = result.material_estimated;
        out["specular_identifiable"] = result.specular_identifiable;
        out["specular_note"] = result.specular_note;
        py::list scores;
        for (const solve::ModelCandidate& c : result.model_choice.scored) {
          scores.append(py::dict(
              py::arg("model") = reflectance::LobeName(c.lobe), py::arg("shininess") = c.shininess,
              py::arg("ambient_term") = ToList(c.ambient_term),
              py::arg("ks_prior_weight") = c.ks_prior_weight,
              py::arg("code_offset") = c.code_offset, py::arg("heldout_cost") = c.heldout_cost,
              py::arg("heldout_pixels") = c.heldout_pixels));
        }
        out["model_scores"] = scores;
        if (const solve::ShadingMisfit& m = result.model_choice.shading; !m.weights.empty()) {
          out["shading_weights"] =
              py::dict(py::arg("band_upper_n_dot_l") = m.weights.upper,
                       py::arg("weight") = m.weights.weight, py::arg("offset") = m.weights.offset,
                       py::arg("heldout_bias") = m.bias, py::arg("heldout_spread") = m.spread,
                       py::arg("rounds") = m.rounds, py::arg("offset_rounds") = m.offset_rounds);
        }
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
      py::arg("max_memory_gb") = py::none(), py::kw_only(), py::arg("light_positions") = py::none(),
      py::arg("camera") = py::none(), py::arg("light_axes") = py::none(),
      py::arg("light_anisotropy") = py::none(), py::arg("distance") = py::none(),
      py::arg("light_distance") = "auto",
      py::arg("weigh_by_shading") = solve::NormalOptions{}.weigh_by_shading,
      py::arg("per_pixel_model") = solve::NormalOptions{}.per_pixel_model,
      R"doc(Recover per-pixel normals and albedo (see `iphong normals`).

images (K, H, W, 3) linear float; light_directions (K, 3) from the surface toward the light;
light_intensities (K, 3) or None (ones); mask (H, W) bool or None; model None (chosen by
held-out prediction among Lambert, Oren-Nayar's rough diffuse term, Phong, Blinn-Phong and a foil
centred on the normal, the normals' integrability deciding between the foil and a highlight:
model_scores lists every candidate), "phong", "blinn-phong" or "normal-centred" (that lobe, its
shininess chosen), "oren-nayar" (its facet slope chosen, in radians, reported as the shininess)
or "lambert" (Woodham); material: dict
with ka, ks, shininess, ambient (and model) when the coefficients are known, else ks is
estimated per pixel; shadow_threshold: observations darker than the model by more than this
fraction of the pixel's brightness count as shadowed. With the model chosen, model_map (H, W) says
per pixel which won its own held-out test: 1 the specular model, 0 Lambert, -1 no normal
(per_pixel_model=False, as `iphong normals --no-pixel-test`, gives every pixel the chosen model
untested and no model_map: under 24 lights or fewer the test is most of the solve), and
shading_weights says how the observations were weighed by N·L (band_upper_n_dot_l, weight,
offset, heldout_bias, heldout_spread, rounds, offset_rounds: a band toward the terminator whose
held-out misfit is biased is weighed down, and the bias the weights leave is taken off its
observations: offset, iterated until it is the bias measured at the normals it places;
weigh_by_shading=False, as `iphong normals --uniform-weights`, weighs every observation alike and
takes nothing off).
Returns normals (H, W, 3), albedo (H, W, 3), specular (H, W, 3: each pixel's ks; not for
lambert), residual (H, W; -1 where no normal was found),
the specular coefficients used or estimated, and a summary. Distant lights are checked as
`iphong normals` checks a light file, with a UserWarning when they look like another frame:
depth_axis_check (Woodham's normals facing away from the camera along each axis: lights whose
depth axis is their x or y) and frame_check (the image-plane reading the normals fit best: y
negated, x and y swapped, ...); image_check says which images disagree with the others
(misfit: per image, the median of abs(observation - model) / the censoring threshold over a sample of
pixels; score: its modified z-score among the images; disagreeing: 0-based indices, with a
UserWarning naming them: a light file out of order, a light's direction or intensity wrong, a
moved object). With 1 or 2 images (material with
kd required) the global solver with smoothness, integrability and boundary priors runs instead and
the result has ambiguity_deg (H, W): the angle the data alone leaves open per pixel; it needs
about 4 kB a masked pixel, and ValueError says so before it starts when that is more than
max_memory_gb (default: three quarters of the machine's).

Near lights (keyword only, as the near-light layout gives them; load_dataset returns them):
light_positions (K, 3) mm in the camera frame (the object at z < 0), camera a dict as camera.json
({fx, fy, cx, cy} in pixels, OpenCV's principal point, or {pixel_size} in mm: orthographic),
light_axes (K, 3) and light_anisotropy (K) for LEDs, distance (mm) a first guess of the object's
distance; light_intensities are then each light's intensity (irradiance x mm^2). The result adds
depth (H, W) mm along the axis, points (H, W, 3) and near (passes, distance). With directions only,
light_distance: "auto" (chosen by held-out prediction, distant lights among the candidates),
"inf" or a distance in pixels; the result adds effective_distance (the candidates' scores).)doc");

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
        out["not_finite_pixels"] = m.not_finite;
        out["missing_pixels"] = m.missing;
        out["error_deg"] = ToArray(m.error_deg);
        if (m.not_finite > 0) {  // as `iphong eval` says it
          py::module_::import("warnings")
              .attr("warn")(std::to_string(m.not_finite) + " of " + std::to_string(m.pixels) +
                            " pixels with ground truth hold no finite normal in the estimate "
                            "(NaN or infinite): scored as missing, 180 degrees");
        }
        return out;
      },
      py::arg("estimate"), py::arg("ground_truth"), py::arg("mask") = py::none(),
      "Angular error statistics (degrees) and the per-pixel error map, over the mask where the "
      "ground truth is non-zero. An estimate that is not finite (NaN or infinite) is a missing "
      "normal, 180 degrees as a zero is: counted in not_finite_pixels, with a warning; "
      "missing_pixels counts both. ValueError when no evaluated pixel has an estimate.");
}

}  // namespace iphong::python
