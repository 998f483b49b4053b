// The plan of a solve, made once per capture and applied to every band: the spread sample of
// pixels it is made on, the observations it copies, the check that the images vary, and the
// model choice, highlight check and shading weights measured on that sample.
#include <algorithm>
#include <optional>
#include <stdexcept>

#include "core/timing.h"
#include "solve/assemble.h"
#include "solve/highlight_check.h"
#include "solve/model_choice.h"
#include "solve/normals.h"
#include "solve/shading_weights.h"

namespace iphong::solve {

using internal::CheckInputs;
using internal::FitSettingsOf;

std::vector<std::size_t> PlanSampleIndices(std::size_t masked_pixels, std::size_t plan_sample) {
  std::vector<std::size_t> indices;
  const std::size_t n = std::min(masked_pixels, plan_sample);
  indices.reserve(n);
  // i·M/n, exact in integers: ascending, distinct, spread evenly, all pixels when n = M.
  for (std::size_t i = 0; i < n; ++i) {
    indices.push_back(
        static_cast<std::size_t>((static_cast<unsigned __int128>(i) * masked_pixels) / n));
  }
  return indices;
}

PhotometricData SubsetObservations(const PhotometricData& data,
                                   const std::vector<std::size_t>& indices) {
  PhotometricData out;
  out.width = data.width;
  out.height = data.height;
  out.images = data.images;
  out.light_directions = data.light_directions;
  out.light_intensities = data.light_intensities;
  out.point_lights = data.point_lights;
  out.perspective = data.perspective;
  AppendObservations(out, data, indices, 0);
  return out;
}

void AppendObservations(PhotometricData& to, const PhotometricData& from,
                        const std::vector<std::size_t>& indices, std::size_t pixel_offset) {
  const std::size_t values = static_cast<std::size_t>(from.images) * 3;
  to.pixels.reserve(to.pixels.size() + indices.size());
  to.values.reserve(to.values.size() + indices.size() * values);
  for (std::size_t i : indices) {
    if (i >= from.pixel_count()) throw std::invalid_argument("sample index beyond the pixels");
    to.pixels.push_back(static_cast<int>(from.pixels[i] + pixel_offset));
    to.values.insert(to.values.end(), from.pixel(i), from.pixel(i) + values);
    if (from.near()) to.points_cam.push_back(from.points_cam[i]);
  }
}

void AppendSampleSpecular(const NormalResult& result, const PhotometricData& data,
                          const std::vector<std::size_t>& indices, std::vector<Vec3f>& ks) {
  if (result.specular.pixels.empty()) return;
  for (std::size_t i : indices) {
    const std::size_t p = static_cast<std::size_t>(data.pixels[i]);
    if (result.residual.pixels[p] < 0) continue;
    // Where the pixel's own test gave it to Lambert its ks is 0 by choice, not a measurement.
    if (!result.model_map.pixels.empty() && result.model_map.pixels[p] == 0) continue;
    const float* v = result.specular.pixels.data() + 3 * p;
    ks.emplace_back(v[0], v[1], v[2]);
  }
}

bool NeedsPlanSample(const NormalOptions& options) {
  return options.model != reflectance::Lobe::kLambert && !options.material_known;
}

void NormalPlan::Use(const ModelCandidate& m) {
  options.model = m.lobe;
  options.shininess = m.shininess;
  options.ambient_term = m.ambient_term;
  options.code_offset = m.code_offset;
  model_choice.chosen = m;
}

void ImageVariation::Add(const PhotometricData& data) {
  images_ = data.images;
  pixels_ += data.pixel_count();
  const std::size_t k3 = static_cast<std::size_t>(data.images) * 3;
  for (std::size_t i = 0; i < data.pixel_count() && !varies_; ++i) {
    const float* v = data.pixel(i);
    lit_ = lit_ || v[0] != 0 || v[1] != 0 || v[2] != 0;
    for (std::size_t c = 3; c < k3 && !varies_; ++c) varies_ = v[c] != v[c % 3];
  }
}

void ImageVariation::Check() const {
  if (images_ > 1 && pixels_ > 0 && !varies_ && lit_) {
    throw std::invalid_argument(
        "the " + std::to_string(images_) + " images are the same at each of the " +
        std::to_string(pixels_) +
        " pixels sampled (the light did not change between the photographs, or one photo was "
        "saved under every name): no normal can be recovered");
  }
}

NormalPlan PlanNormals(const PhotometricData& sample, const NormalOptions& options,
                       const std::vector<Vec3d>* starts) {
  CheckInputs(sample, options);
  if (starts && starts->size() != sample.pixel_count()) {
    throw std::invalid_argument("plan: one start per pixel of the sample needed");
  }
  ImageVariation variation;
  variation.Add(sample);
  variation.Check();
  NormalPlan plan;
  plan.options = options;
  plan.requested_model = options.model;
  NormalOptions& o = plan.options;
  if (!NeedsPlanSample(o)) return plan;
  const auto start = Clock::now();
  ModelChoiceSettings choice;
  choice.fit = FitSettingsOf(o);
  choice.sample = o.model_sample;
  choice.search_candidates = o.search_candidates;
  choice.threads = o.threads;
  choice.starts = starts;
  plan.model_choice = ChooseModel(
      sample, ModelFamily(o.choose_model ? std::nullopt : std::optional(o.model)), choice);
  plan.Use(plan.model_choice.chosen);
  CheckHighlight(sample, plan);
  if (o.weigh_by_shading && !plan.model_choice.fold.empty()) {
    const std::vector<std::size_t> pixels = SpreadIndices(sample.pixel_count(), o.model_sample);
    std::vector<Vec3d> sub;
    if (starts) {
      for (std::size_t i : pixels) sub.push_back((*starts)[i]);
    }
    plan.model_choice.shading = EstimateShadingWeights(
        sample, internal::PlanFitSettings(plan), pixels, plan.model_choice.fold,
        o.search_candidates, o.threads, starts ? &sub : nullptr);
    o.shading_weights = plan.model_choice.shading.weights;
  }
  plan.model_seconds = SecondsSince(start);
  return plan;
}

}  // namespace iphong::solve
