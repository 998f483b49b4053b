// What a normals run checks of what it was given and reports in metrics.json: the images'
// encoding, the light file's frame and depth axis (a warning, or with --strict an error), the
// images that disagree with the others, and the angular errors against ground truth
// (normals_command.h).
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "integrate/frame_check.h"
#include "io/dataset.h"
#include "io/image_io.h"
#include "iphong/console.h"
#include "iphong/normals_command.h"
#include "solve/depth_axis.h"
#include "solve/image_check.h"
#include "solve/metrics.h"
#include "solve/normals.h"
#include "solve/reading_check.h"

namespace iphong::cli {

nlohmann::json AngularErrorJson(const solve::AngularErrorMetrics& m) {
  return {{"evaluated_pixels", m.pixels},
          {"mean_angular_error_deg", m.mean_deg},
          {"median_angular_error_deg", m.median_deg},
          {"fraction_below_5_deg", m.below_5_deg},
          {"fraction_below_10_deg", m.below_10_deg},
          {"fraction_below_20_deg", m.below_20_deg},
          {"missing_pixels", m.missing}};
}

nlohmann::json FrameCheckJson(const integrate::FrameCheckResult& r) {
  nlohmann::json readings = nlohmann::json::array();
  for (const integrate::FrameReadingScore& s : r.scores) {
    readings.push_back({{"reading", integrate::PlaneReadingName(s.reading)},
                        {"silhouette_cos", s.silhouette_cos},
                        {"consistency_deg", s.consistency_deg}});
  }
  return {{"better", integrate::PlaneReadingName(r.better)},
          {"silhouette_pixels", r.silhouette_pixels},
          {"readings", readings}};
}

nlohmann::json CheckEncoding(const NormalsCommandOptions& o, const io::Dataset& dataset,
                             const solve::PhotometricData& data,
                             const solve::NormalOptions& options) {
  if (!dataset.encoding.assumed || data.images < 6 || data.pixel_count() == 0) return nullptr;
  const solve::ReadingComparison c =
      solve::CompareReadings(data, io::DecodeSrgb, solve::ReadingSettings(options));
  const bool display = c.reread_better;
  const double z = c.gain_error > 0 ? std::abs(c.gain) / c.gain_error : 0.0;
  if (display) {
    char text[480];
    std::snprintf(text, sizeof text,
                  "the images state no colour space and were read as linear, but a Lambertian "
                  "fit finds them more likely decoded as sRGB (display-encoded): held-out "
                  "log-likelihood %+.3g +- %.2g per pixel, %.1f standard errors",
                  c.gain, c.gain_error, z);
    Warn(o.dataset + ": " + text +
         ": if they were saved for a screen (a renderer's or an editor's PNG), pass --encoding "
         "srgb; --encoding linear keeps this reading without the check");
  } else {
    Say(o.common,
        "Encoding: linear kept (the files state no colour space; decoded as sRGB the photos are "
        "less likely: held-out log-likelihood %+.3g +- %.2g per pixel, %.1f standard errors, "
        "%.2f s)\n",
        c.gain, c.gain_error, z, c.seconds);
  }
  return {{"encoding", "linear"},
          {"srgb_better", display},
          {"heldout_cost_linear", c.cost_as_given},
          {"heldout_cost_srgb", c.cost_reread},
          {"loglik_gain_srgb", c.gain},
          {"loglik_gain_error", c.gain_error},
          {"pixels", c.pixels},
          {"seconds", c.seconds}};
}

namespace {

// What a frame check found, said of the light file: a warning, or with --strict an error.
void SayLightFrame(const NormalsCommandOptions& o, const io::Dataset& dataset,
                   const std::string& found) {
  const std::string& lights = dataset.files.lights_path;
  const std::string text = (lights.empty() ? o.dataset : lights) +
                           ": the light directions look like another frame: " + found +
                           "; check the file's axes (x right, y up toward row 0, z toward the "
                           "camera)" +
                           (o.strict ? "" : ", or pass --strict to refuse such a file");
  if (o.strict) throw std::runtime_error(text);
  Warn(text);
}

}  // namespace

std::optional<integrate::FrameCheckResult> CheckLightFrame(const NormalsCommandOptions& o,
                                                           const io::Dataset& dataset,
                                                           const ImageF& normals,
                                                           const Mask& with_normal) {
  if (solve::MostLightsBehind(dataset.light_directions)) return std::nullopt;
  integrate::FrameCheckOptions check;
  check.threads = o.common.threads;
  integrate::FrameCheckResult frame = integrate::CheckNormalFrame(normals, with_normal, check);
  if (!frame.message.empty()) SayLightFrame(o, dataset, frame.message);
  return frame;
}

nlohmann::json CheckDepthAxis(const NormalsCommandOptions& o, const io::Dataset& dataset,
                              const solve::PhotometricData& data) {
  if (data.near()) return nullptr;
  return ReportDepthAxis(o, dataset, data.light_directions, solve::CheckDepthAxis(data));
}

nlohmann::json ReportDepthAxis(const NormalsCommandOptions& o, const io::Dataset& dataset,
                               const std::vector<Vec3d>& lights_cam,
                               const solve::DepthAxisCheck& c) {
  if (c.pixels == 0 || solve::MostLightsBehind(lights_cam)) return nullptr;
  if (!c.message.empty()) SayLightFrame(o, dataset, c.message);
  nlohmann::json j = {{"pixels", c.pixels},
                      {"facing_away", c.facing_away},
                      {"best_axis", c.BestAxisName()},
                      {"best_facing_away", c.best_facing}};
  if (!c.message.empty()) j["warning"] = c.message;
  return j;
}

nlohmann::json CheckImagesAgree(const NormalsCommandOptions& o, const io::Dataset& dataset,
                                const solve::PhotometricData& data,
                                const solve::NormalResult& result,
                                const solve::NormalOptions& options) {
  solve::ImageCheckOptions check;
  check.saturation = options.saturation;
  check.shadow_threshold = options.shadow_threshold;
  if (options.material_known) check.known_ks = options.ks;
  check.threads = o.common.threads;
  const solve::ImageCheck c = solve::CheckImages(data, result, check);
  if (!c.checked) return nullptr;
  nlohmann::json images = nlohmann::json::array();
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; };
  for (int j = 0; j < data.images; ++j) {
    nlohmann::json image = {{"misfit", number(c.misfit[j])},
                            {"score", number(c.score[j])},
                            {"observations", c.observations[j]}};
    if (static_cast<std::size_t>(j) < dataset.filenames.size()) {
      image["file"] = dataset.filenames[j];
    }
    images.push_back(image);
  }
  nlohmann::json disagreeing = nlohmann::json::array();
  std::string names, lines;
  double least = std::numeric_limits<double>::infinity();
  for (const int j : c.disagreeing) {
    const std::string file = static_cast<std::size_t>(j) < dataset.filenames.size()
                                 ? dataset.filenames[j]
                                 : "image " + std::to_string(j + 1);
    disagreeing.push_back(file);
    names += (names.empty() ? "" : ", ") + file;
    lines += (lines.empty() ? "" : ", ") + std::to_string(j + 1);
    least = std::min(least, c.misfit[j]);
  }
  if (!c.disagreeing.empty()) {
    const std::string& light_file = dataset.files.lights_path;
    char figures[200];
    std::snprintf(figures, sizeof figures,
                  "at half of %zu pixels the model misses %s by more than %.2g shadow thresholds "
                  "(the typical image: %.2g)",
                  c.pixels, c.disagreeing.size() == 1 ? "it" : "each", least, c.typical_misfit);
    Warn((light_file.empty() ? o.dataset : light_file) + ": " +
         (c.disagreeing.size() == 1 ? "image " : "images ") + names +
         (c.disagreeing.size() == 1 ? " disagrees" : " disagree") + " with the other " +
         std::to_string(data.images - static_cast<int>(c.disagreeing.size())) + ": " + figures +
         // Lights by their order (a light file may begin with a count line).
         "; check light" + (c.disagreeing.size() == 1 ? " " : "s ") + lines + " of the light file" +
         ", the images' order, their intensities, and whether the object or camera moved");
  }
  return {{"pixels", c.pixels},
          {"typical_misfit", c.typical_misfit},
          {"score_limit", solve::kImageDisagreementZ},
          {"heldout", c.heldout},
          {"seconds", c.seconds},
          {"disagreeing", disagreeing},
          {"images", images}};
}

}  // namespace iphong::cli
