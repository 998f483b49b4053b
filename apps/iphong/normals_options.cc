// `iphong normals`: what it reads into the solver's options, and how it reports the capture and
// the material (shared by the in-memory run, the bands and the near-light run).
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "io/dataset.h"
#include "iphong/normals_command.h"
#include "reflectance/material.h"

namespace iphong::cli {

nlohmann::json NormalsInputJson(const io::Dataset& d) {
  nlohmann::json counts = nlohmann::json::array();
  for (std::size_t j = 0; j < d.image_counts.size(); ++j) {
    counts.push_back({{"file", d.filenames[j]},
                      {"saturated_pixels", d.image_counts[j].saturated},
                      {"black_pixels", d.image_counts[j].black}});
  }
  return {{"layout", d.files.layout},
          {"order", d.files.order},
          {"lights", d.files.lights_path},
          {"lights_format", d.files.lights_format},
          {"intensities", d.files.intensities_source},
          {"mask", d.files.mask_path},
          {"encoding", d.encoding.encoding == io::Encoding::kSrgb ? "srgb" : "linear"},
          {"encoding_reason", d.encoding.reason},
          {"file_size", {d.file_width, d.file_height}},
          {"size", {d.mask.width, d.mask.height}},
          {"ground_truth", d.files.ground_truth_path},
          {"images", counts}};
}

nlohmann::json EstimatedMaterialJson(const solve::NormalResult& result) {
  return {{"model", reflectance::LobeName(result.model)},
          {"ks", {result.ks[0], result.ks[1], result.ks[2]}},
          {"shininess", result.shininess},
          {"ambient", {1, 1, 1}},
          {"ka", {result.ambient_term[0], result.ambient_term[1], result.ambient_term[2]}},
          {"comment", "estimated by iphong normals: " + result.specular_note}};
}

nlohmann::json ShadingWeightsJson(const solve::ShadingMisfit& m) {
  if (m.weights.empty()) return nullptr;
  return {{"band_upper_n_dot_l", m.weights.upper},
          {"weight", m.weights.weight},
          {"offset", m.weights.offset},
          {"heldout_bias", m.bias},
          {"heldout_spread", m.spread},
          {"observations", m.observations},
          {"rounds", m.rounds},
          {"offset_rounds", m.offset_rounds}};
}

std::string ShadingWeightsLine(const solve::ShadingMisfit& m) {
  std::string bands;
  for (std::size_t b = 0; b < m.weights.weight.size(); ++b) {
    if (m.weights.weight[b] >= kShownWeight) continue;
    char band[64];
    std::snprintf(band, sizeof band, "%sN.L < %.2f x%.2f", bands.empty() ? "" : ", ",
                  m.weights.upper[b], m.weights.weight[b]);
    bands += band;
  }
  if (bands.empty()) return "";
  return "Oblique observations weighed down where the model's held-out misfit is biased, and the "
         "bias left taken off them: " +
         bands + " (" + std::to_string(m.rounds) +
         " rounds; metrics.json shading_weights; --uniform-weights: none)";
}

std::string MaterialLabel(const solve::NormalOptions& options, const solve::NormalResult& result) {
  return options.material_known                         ? "known (material.json)"
         : options.model == reflectance::Lobe::kLambert ? "lambertian"
         : result.material_estimated                    ? "estimated"
                                                        : "lambertian (chosen)";
}

nlohmann::json SolveMetricsJson(const solve::NormalOptions& options,
                                const solve::NormalResult& result, std::size_t specular_pixels,
                                std::size_t chosen_pixels) {
  nlohmann::json metrics;
  metrics["model"] = reflectance::LobeName(result.model);
  metrics["model_seconds"] = result.summary.model_seconds;
  metrics["solve_seconds"] = result.summary.solve_seconds;
  metrics["iterations"] = result.summary.iterations;
  if (!result.model_choice.scored.empty()) {
    nlohmann::json scores = nlohmann::json::array();
    for (const solve::ModelCandidate& m : result.model_choice.scored) {
      scores.push_back({{"model", reflectance::LobeName(m.lobe)},
                        {"shininess", m.shininess},
                        {"ambient_term", {m.ambient_term[0], m.ambient_term[1], m.ambient_term[2]}},
                        {"ks_prior_weight", m.ks_prior_weight},
                        {"code_offset", m.code_offset},
                        {"heldout_cost", m.heldout_cost},
                        {"heldout_error", m.heldout_error},
                        {"fold_angle_deg", m.fold_angle_deg},
                        {"heldout_pixels", m.heldout_pixels}});
    }
    metrics["model_choice"] = {{"chosen", reflectance::LobeName(result.model)},
                               {"pixels_choosing_it", specular_pixels},
                               {"pixels_choosing_lambert", chosen_pixels - specular_pixels},
                               {"shininess", result.shininess},
                               {"pixels", result.model_choice.pixels},
                               // false with --no-pixel-test: every pixel took the chosen model
                               {"pixel_test", options.per_pixel_model},
                               {"integer_code_step", result.model_choice.code_step},
                               {"code_offset", result.code_offset},
                               {"scores", scores}};
    if (!options.per_pixel_model) {
      // No pixel chose: every one took the chosen model (a count of 0 would say none did).
      metrics["model_choice"].erase("pixels_choosing_it");
      metrics["model_choice"].erase("pixels_choosing_lambert");
    }
  }
  if (auto w = ShadingWeightsJson(result.model_choice.shading); !w.is_null()) {
    metrics["shading_weights"] = w;
  }
  metrics["dark_pixels"] = result.summary.dark_pixels;
  metrics["underdetermined_pixels"] = result.summary.underdetermined_pixels;
  metrics["material"] = MaterialLabel(options, result);
  if (!result.specular_note.empty()) metrics["specular_note"] = result.specular_note;
  return metrics;
}

void SayModelAndFlags(const CommonOptions& common, const solve::NormalResult& result) {
  if (result.material_estimated && result.model == reflectance::Lobe::kOrenNayar) {
    Say(common, "Model oren-nayar, facet slope %.3f rad (%s)\n", result.shininess,
        result.specular_note.c_str());
  } else if (result.material_estimated) {
    Say(common, "Model %s, shininess %.1f; ks median [%.3f %.3f %.3f] (%s)\n",
        reflectance::LobeName(result.model).c_str(), result.shininess, result.ks[0], result.ks[1],
        result.ks[2], result.specular_note.c_str());
  } else if (!result.specular_note.empty()) {
    Say(common, "%s\n", result.specular_note.c_str());
  }
  if (std::string line = ShadingWeightsLine(result.model_choice.shading); !line.empty()) {
    Say(common, "%s\n", line.c_str());
  }
  if (result.summary.dark_pixels + result.summary.underdetermined_pixels > 0) {
    Say(common,
        "%zu pixels dark in every image and %zu with fewer than 3 usable lights: "
        "flagged -1 in residual.exr\n",
        result.summary.dark_pixels, result.summary.underdetermined_pixels);
  }
}

solve::NormalOptions NormalOptionsFor(const NormalsCommandOptions& o, const io::Dataset& d) {
  solve::NormalOptions options;
  options.discard_dark = o.discard_dark;
  options.discard_bright = o.discard_bright;
  options.threads = o.common.threads;
  options.shadow_threshold = o.shadow_threshold;
  options.irls_rounds = o.irls_rounds;
  options.color_residuals = !o.fast;
  options.weigh_by_shading = !o.uniform_weights;
  options.per_pixel_model = o.pixel_test;
  if (d.material && !o.ignore_material) {
    options.model = d.material->model;
    options.material_known = true;
    options.ambient_term = d.material->ambient.cwiseProduct(d.material->material.ka);
    options.ks = d.material->material.ks;
    options.shininess = d.material->material.shininess;
    if (d.material->kd_known) options.known_albedo = d.material->material.kd;
  }
  if (o.model) {
    options.model = reflectance::ParseLobe(*o.model);
    options.choose_model = false;  // the user's lobe: only its shininess is chosen
  }
  return options;
}

}  // namespace iphong::cli
