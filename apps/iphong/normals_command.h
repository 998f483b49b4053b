// `iphong normals`: the options, and the run in bands of rows for captures larger than the
// memory limit (normals_bands.cc); the in-memory run is in cmd_normals.cc.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "calibrate/lights.h"
#include "integrate/frame_check.h"
#include "io/capture_bands.h"
#include "io/output_folder.h"
#include "iphong/commands.h"
#include "near/effective_distance.h"
#include "near/near.h"
#include "solve/depth_axis.h"
#include "solve/metrics.h"
#include "solve/normals.h"

namespace iphong::cli {

struct NormalsCommandOptions {
  std::string dataset;
  std::string output_dir;
  std::optional<std::string> model;
  bool ignore_material = false;
  double discard_dark = 0.3, discard_bright = 0.1;
  std::string convention = "opengl";
  double shadow_threshold = solve::NormalOptions{}.shadow_threshold;
  int irls_rounds = solve::NormalOptions{}.irls_rounds;
  bool fast = false;
  bool uniform_weights = false;  // no weights by N·L (NormalOptions::weigh_by_shading off)
  bool pixel_test = true;  // each pixel's Lambert-or-lobe test (NormalOptions::per_pixel_model)
  bool integrate = false;
  bool estimate_intensities = false;
  bool strict = false;     // a light file in another frame is an error, not a warning
  double error_range = 0;  // error.png's top of scale in degrees; 0 = from the data
  double distance = 0;     // near lights: the object's distance along the axis (mm), 0 = find it
  // Directions only: "auto" (chosen by held-out prediction, ∞ among the candidates), "inf"
  // (distant lights) or a distance in pixels.
  std::string light_distance = "auto";
  int band_rows = 0;  // > 0: in bands of this many rows whatever the memory limit
  CaptureFlags capture;
  CommonOptions common;
};

// What the run needs in memory at once: the whole capture's masked observations and full-size
// results, or per row of a band.
struct NormalsMemory {
  double whole_bytes = 0;
  double fixed_bytes = 0;    // in bands: the mask, the plan sample, the libraries
  double per_row_bytes = 0;  // in bands: per row of the working size
  // In bands, beside fixed_bytes when the effective light distance is sought: the whole-field
  // part (near::kEffectiveDistanceBytesPerPixel per masked pixel).
  double field_bytes = 0;
  // The rows a band may have within `limit` bytes; 0 when not even one fits.
  int BandRows(double limit, int height) const;
};
NormalsMemory EstimateNormalsMemory(const io::CaptureBands& capture,
                                    const solve::NormalOptions& options, int threads);

nlohmann::json NormalsInputJson(const io::Dataset& d);
// The angular-error figures of metrics.json (normals) and of `iphong eval`'s output.
nlohmann::json AngularErrorJson(const solve::AngularErrorMetrics& m);

// material.json as `iphong normals` writes an estimated material.
nlohmann::json EstimatedMaterialJson(const solve::NormalResult& result);
// metrics.json's shading_weights (null when none were measured) and the line saying which bands
// of N·L were weighed below kShownWeight (empty when none was).
constexpr double kShownWeight = 0.9;
nlohmann::json ShadingWeightsJson(const solve::ShadingMisfit& m);
std::string ShadingWeightsLine(const solve::ShadingMisfit& m);

// metrics.json's "material": known, lambertian, estimated or lambertian (chosen).
std::string MaterialLabel(const solve::NormalOptions& options, const solve::NormalResult& result);

// The solve's part of metrics.json, the same whole and in bands: the model and its choice (each
// candidate's held-out score, the pixels each model took: `specular_pixels` of `chosen_pixels`
// in model.exr), the shading weights, the timings and counts, and the material.
nlohmann::json SolveMetricsJson(const solve::NormalOptions& options,
                                const solve::NormalResult& result, std::size_t specular_pixels,
                                std::size_t chosen_pixels);
// The lines a run prints after its timings, whole or in bands: the model and its ks (or why
// there is none), the weights by N·L, the pixels flagged.
void SayModelAndFlags(const CommonOptions& common, const solve::NormalResult& result);

// The light file's frame, checked on the normals it gave (integrate/frame_check.h: a file in
// another image-plane frame returns the normals in that frame): a warning naming the reading
// that fits, or with --strict an error. Nothing for a file with most lights behind the object,
// which has its own warning. `normals` may be the capture's field averaged down (bands).
std::optional<integrate::FrameCheckResult> CheckLightFrame(const NormalsCommandOptions& o,
                                                           const io::Dataset& dataset,
                                                           const ImageF& normals,
                                                           const Mask& with_normal);
nlohmann::json FrameCheckJson(const integrate::FrameCheckResult& r);

// The light file's depth axis, from Woodham's unconstrained normals on a sample of `data`
// (solve/depth_axis.h: a file whose x or y is the axis toward the camera): a warning naming the
// axis, or with --strict an error. Before the solve, so a long run does not hide it. Nothing for
// near lights, or a file with most lights behind the object (its own warning). Returns
// metrics.json's "depth_axis_check", or null when not checked.
nlohmann::json CheckDepthAxis(const NormalsCommandOptions& o, const io::Dataset& dataset,
                              const solve::PhotometricData& data);
// The same from counts added up elsewhere (bands: every band of the first pass); `lights` the
// capture's directions.
nlohmann::json ReportDepthAxis(const NormalsCommandOptions& o, const io::Dataset& dataset,
                               const std::vector<Vec3d>& lights, const solve::DepthAxisCheck& c);

// Which images disagree with the others (solve/image_check.h), from how each agrees with a render
// of `result`, a solve of `data`: a warning naming them and what to check (the light file's
// order and those lines, the intensities, a moved object). metrics.json's "image_check", or null
// when not checked (fewer than 6 images, the one- and two-image solve).
nlohmann::json CheckImagesAgree(const NormalsCommandOptions& o, const io::Dataset& dataset,
                                const solve::PhotometricData& data,
                                const solve::NormalResult& result,
                                const solve::NormalOptions& options);

// Files that state no colour space were read as linear (io::EncodingChoice::assumed): whether the
// data agree (solve/reading_check.h), a warning when decoding them as sRGB predicts held-out
// photos clearly better. metrics.json's "encoding_check", or null when not asked.
nlohmann::json CheckEncoding(const NormalsCommandOptions& o, const io::Dataset& dataset,
                             const solve::PhotometricData& data,
                             const solve::NormalOptions& options);

// --estimate-intensities (normals_intensities.cc): the estimate, checked against the capture's
// intensity file or, with none, against equal lights. Refuses (std::runtime_error, nothing
// written) where the two put the normals more than a degree apart and the images cannot say the
// estimate is right: beside a file the images do not contradict, or within the estimate's own
// error of equal lights (unless --intensities none asked for it unchecked); warns otherwise.
// `metrics` is metrics.json's "estimated_intensities".
// Where the check ran the command's own run under the estimate (distant lights), it is kept in
// `run` with its log lines, and the command writes it rather than solving it again.
struct EstimatedIntensities {
  calibrate::IntensityEstimate estimate;
  nlohmann::json metrics;
  std::optional<near::EffectiveDistanceResult> run;
  std::vector<std::string> run_log;
};
EstimatedIntensities EstimateCheckedIntensities(const NormalsCommandOptions& o,
                                                const io::Dataset& dataset,
                                                const solve::PhotometricData& observations);

// The solver's options from the command's flags and the capture's material.json.
solve::NormalOptions NormalOptionsFor(const NormalsCommandOptions& o, const io::Dataset& d);

// Normals in bands of `band_rows` rows (solve/bands.h), each band's results written as it is
// done: normals.exr/.png, albedo.exr, residual.exr, specular.exr, model.exr; then albedo.png from
// the written albedo.exr, material.json and metrics.json. Commits `out`.
// `field`: the run goes through near::SolveEffectiveDistanceInBands (the in-memory run's result:
// the choice of D, or with --light-distance inf the foil's refit at D = ∞); false when its
// whole-field part would not fit (distant lights and no refit, with a warning unless inf).
void RunNormalsInBands(const NormalsCommandOptions& o, io::OutputFolder& out,
                       io::CaptureBands& capture, int band_rows, const NormalsMemory& memory,
                       bool field, double started_seconds_ago);

// A near-light capture's solve (normals_near.cc): the loop of near/near.h on the capture's point
// lights, with the camera as the working images see it.
struct NearRun {
  near::NearResult result;
  geometry::HeightMapFrame frame;
};
NearRun SolveNearCapture(const NormalsCommandOptions& o, const io::Dataset& d,
                         const solve::PhotometricData& observations,
                         const solve::NormalOptions& options);
// The observations of `sample` pixels spread over the mask as the near run's last pass saw them:
// its point lights, seen from the points of its surface (for checking the images against its
// result).
solve::PhotometricData NearRunData(const io::Dataset& d, const solve::PhotometricData& observations,
                                   const NearRun& run, std::size_t sample);
// Directions only (near/effective_distance.h): the distant solve and, unless --light-distance
// inf, the effective distance chosen (or given) and the near passes; metrics.json's
// "effective_distance".
// With `done` (a run already made on the same data and options, and its log lines) that run is
// reported instead of a new one.
near::EffectiveDistanceResult SolveWithEffectiveDistance(
    const NormalsCommandOptions& o, const solve::PhotometricData& data,
    const solve::NormalOptions& options, nlohmann::json& metrics,
    std::optional<near::EffectiveDistanceResult> done = std::nullopt,
    const std::vector<std::string>& done_log = {});
// The options of both runs (whole and in bands) from --light-distance; throws
// std::invalid_argument on a bad value.
near::EffectiveDistanceOptions EffectiveDistanceOptionsFor(const NormalsCommandOptions& o,
                                                           const solve::NormalOptions& options);
// metrics.json's "effective_distance".
nlohmann::json EffectiveDistanceJson(const near::EffectiveDistanceResult& r);

// depth.exr (mm along the axis, 0 outside), the surface files (mesh.ply in mm, height.png) and
// metrics.json's "near_lights" (passes, distance, depth RMSE against Depth_gt.mat).
void WriteNearOutputs(io::OutputFolder& out, const NearRun& run, const io::Dataset& d,
                      nlohmann::json& metrics, const CommonOptions& common);

}  // namespace iphong::cli
