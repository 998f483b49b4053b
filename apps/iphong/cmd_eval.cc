// `iphong eval EST GT`: the angular errors of any normal map against ground truth (a dataset
// folder's Normal_gt.mat, or another map), the same figures `iphong normals` reports.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "io/dataset.h"
#include "io/image_io.h"
#include "io/output_folder.h"
#include "io/visualize.h"
#include "iphong/commands.h"
#include "iphong/console.h"
#include "iphong/normals_command.h"
#include "solve/metrics.h"

namespace iphong::cli {
namespace {

struct EvalOptions {
  std::string estimate, ground_truth, mask;
  std::string error_map;
  double error_range = 0;  // degrees at the top of the colour scale; 0 = from the data
  std::string convention = "opengl";
  CommonOptions common;
};

void RunEval(const EvalOptions& o) {
  const MemoryLimit memory = o.common.memory();
  const ImageF estimate = io::ReadNormalMap(o.estimate, o.convention == "directx", nullptr, memory);
  // An albedo handed in by mistake was scored as normals without a word (75 degrees); maps from
  // other tools may be unnormalized (antialiased edges), so this is said, not refused, and the
  // angles are those of the directions.
  {
    std::size_t with_normal = 0, off = 0, first = 0;
    for (std::size_t p = 0; p < estimate.pixel_count(); ++p) {
      const float* v = estimate.pixels.data() + 3 * p;
      const double length =
          std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
      if (!(length > 0)) continue;
      ++with_normal;
      if (std::abs(length - 1) > 0.01 && off++ == 0) first = p;
    }
    if (2 * off > with_normal) {
      const float* v = estimate.pixels.data() + 3 * first;
      char line[320];
      std::snprintf(
          line, sizeof line,
          "%s: %zu of %zu normals are not unit length (|n| = %.3g at column %zu, row %zu): "
          "is it a normal map (an albedo or a picture saved as EXR reads like this)? "
          "Scored by direction",
          o.estimate.c_str(), off, with_normal,
          std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]),
          first % estimate.width, first / estimate.width);
      Warn(line);
    }
  }
  ImageF truth;
  Mask mask;
  std::string truth_name = o.ground_truth;
  if (std::filesystem::is_directory(o.ground_truth)) {
    io::DatasetLoadOptions load;
    load.load_images = false;
    load.memory = memory;
    io::Dataset d = io::LoadDataset(o.ground_truth, load);
    if (d.normal_gt.pixels.empty()) {
      throw std::runtime_error(o.ground_truth + ": no ground truth (Normal_gt.mat or normal.txt)");
    }
    truth = d.normal_gt;
    truth_name = o.ground_truth + "/Normal_gt.mat";
    if (d.mask.width == truth.width && d.mask.height == truth.height) mask = d.mask;
  } else {
    truth = io::ReadNormalMap(o.ground_truth, o.convention == "directx", nullptr, memory);
  }
  if (estimate.width != truth.width || estimate.height != truth.height) {
    throw std::runtime_error(o.estimate + ": is " + SizeText(estimate.width, estimate.height) +
                             ", the ground truth " + truth_name + " is " +
                             SizeText(truth.width, truth.height));
  }
  if (mask.width == 0) mask = Mask(truth.width, truth.height, true);
  if (!o.mask.empty()) {
    mask = io::ReadMask(o.mask, memory);
    if (mask.width != truth.width || mask.height != truth.height) {
      throw std::runtime_error(o.mask + ": is " + SizeText(mask.width, mask.height) +
                               ", the normal maps are " + SizeText(truth.width, truth.height));
    }
  }
  solve::AngularErrorMetrics m;
  try {
    m = solve::CompareNormals(estimate, truth, mask);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(o.estimate + ": " + e.what() + " (" + truth_name +
                             (o.mask.empty() ? "" : ", mask " + o.mask) + ")");
  }
  if (m.not_finite > 0) {  // counted as missing normals, as a 0 is: a mean of 180° is no method's
    Warn(o.estimate + ": " + std::to_string(m.not_finite) + " of " + std::to_string(m.pixels) +
         " pixels with ground truth hold no finite normal (NaN or infinite; the first at column " +
         std::to_string(m.first_not_finite % truth.width) + ", row " +
         std::to_string(m.first_not_finite / truth.width) + "): scored as missing, 180 degrees");
  }
  if (!o.error_map.empty()) {
    io::WriteSingleOutputFile("eval", o.error_map, o.common.overwrite,
                              {o.estimate, o.ground_truth, o.mask}, [&](const std::string& temp) {
                                io::WriteErrorMap(temp, m.error_deg, mask,
                                                  o.error_range > 0
                                                      ? o.error_range
                                                      : io::ErrorMapScale(m.error_deg, mask));
                              });
  }
  std::printf("%s\n", AngularErrorJson(m).dump(2).c_str());
}

}  // namespace

void AddEvalCommand(CLI::App& app) {
  auto e = std::make_shared<EvalOptions>();
  auto* eval = app.add_subcommand("eval", "Angular error of a normal map against ground truth");
  eval->add_option("estimate", e->estimate,
                   "Estimated normals: a float map (EXR, TIFF: xyz), a picture (PNG, JPEG, TGA: "
                   "(n + 1)/2) or a .mat (Normal_gt)")
      ->required();
  eval->add_option("ground_truth", e->ground_truth,
                   "Dataset directory, Normal_gt.mat or a normal map (as the estimate)")
      ->required();
  eval->add_option("--mask", e->mask, "Mask image (nonzero = evaluate)");
  eval->add_option("--error-range", e->error_range,
                   "Degrees at the top of the error map's colour scale, so maps of several runs "
                   "compare (default: from the data, the 95th percentile rounded up)")
      ->check(Positive());
  eval->add_option("--error-map", e->error_map,
                   "Write the error picture (PNG) here (a new file, or --overwrite)");
  eval->add_flag("--overwrite", e->common.overwrite, "Replace an existing --error-map file");
  eval->add_option("--normal-map-convention", e->convention,
                   "Green axis of normal maps stored as pictures (PNG, JPEG)")
      ->check(CLI::IsMember({"opengl", "directx"}))
      ->capture_default_str();
  AddMemoryOption(eval, e->common);
  eval->callback([e] { RunEval(*e); });
}

}  // namespace iphong::cli
