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

solve::NormalOptions NormalOptionsFor(const NormalsCommandOptions& o, const io::Dataset& d) {
  solve::NormalOptions options;
  options.discard_dark = o.discard_dark;
  options.discard_bright = o.discard_bright;
  options.threads = o.common.threads;
  options.shadow_threshold = o.shadow_threshold;
  options.irls_rounds = o.irls_rounds;
  options.color_residuals = !o.fast;
  options.weigh_by_shading = !o.uniform_weights;
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
