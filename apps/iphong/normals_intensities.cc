// `iphong normals --estimate-intensities`: the lights' intensities estimated from the photos and
// checked against the only other set the user has: the capture's intensity file, or with none,
// equal lights.
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>

#include "calibrate/lights.h"
#include "io/dataset.h"
#include "iphong/console.h"
#include "iphong/normals_command.h"

namespace iphong::cli {

EstimatedIntensities EstimateCheckedIntensities(const NormalsCommandOptions& o,
                                                const io::Dataset& dataset,
                                                const solve::PhotometricData& observations) {
  calibrate::IntensityOptions intensity_options;
  intensity_options.threads = o.common.threads;
  EstimatedIntensities out;
  try {
    out.estimate = calibrate::EstimateIntensities(observations, intensity_options);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(o.dataset + ": --estimate-intensities: " + e.what());
  }
  const calibrate::IntensityEstimate& estimate = out.estimate;
  Say(o.common, "Estimated the %d lights' intensities in %.2f s (eigenvalue gap %.1f%s)\n",
      observations.images, estimate.seconds, estimate.eigen_gap,
      estimate.code_offset > 0 ? "; integer codes taken as truncated" : "");
  out.metrics = {{"seconds", estimate.seconds},
                 {"eigen_gap", estimate.eigen_gap},
                 {"lambert_residual", estimate.lambert_residual}};

  // Each set's run as this command makes it (the effective distance, and with it the foil's
  // refit), so the figure compares the normals it would write. The estimate's run is the one the
  // command writes when the estimate is used: kept, with its lines, not made twice; the other
  // set's run is quiet.
  std::function<solve::NormalResult(const solve::PhotometricData&)> whole_run;
  if (!dataset.files.near.present()) {
    whole_run = [&](const solve::PhotometricData& under) {
      near::EffectiveDistanceOptions e =
          EffectiveDistanceOptionsFor(o, NormalOptionsFor(o, dataset));
      const bool estimate_run = under.light_intensities == estimate.light_intensities;
      std::vector<std::string> lines;
      e.log = nullptr;
      if (estimate_run) e.log = [&lines](const std::string& line) { lines.push_back(line); };
      near::EffectiveDistanceResult r = near::SolveEffectiveDistance(under, e);
      if (!estimate_run) return r.normals;
      out.run = std::move(r);
      out.run_log = std::move(lines);
      return out.run->normals;
    };
  }
  const auto compare = [&](const std::vector<Rgb>& other) {
    return calibrate::CompareIntensities(observations, other, estimate.light_intensities,
                                         NormalOptionsFor(o, dataset), whole_run);
  };
  const auto figures = [](const calibrate::IntensityComparison& c) {
    return nlohmann::json{{"median_relative_difference", c.median_relative},
                          {"max_relative_difference", c.max_relative},
                          {"normals_moved_deg", c.normals_moved_deg},
                          {"seconds", c.seconds}};
  };

  // EstimateIntensities needs 4 images or more, so both runs below are per-pixel solves.
  if (dataset.files.intensities_from_file) {
    const std::string& source = dataset.files.intensities_source;
    const calibrate::IntensityComparison c = compare(observations.light_intensities);
    out.metrics["against_file"] = figures(c);
    out.metrics["against_file"]["file"] = source;
    char text[400];
    std::snprintf(text, sizeof text,
                  "%s: the estimated intensities differ from this file's by %.1f%% (median; at "
                  "most %.1f%%), and the normals under the two by %.2f deg on average",
                  source.c_str(), 100 * c.median_relative, 100 * c.max_relative,
                  c.normals_moved_deg);
    // Past a degree the images cannot say which set is right (the estimate reads what Lambert's
    // law explains in them, cast shadows, interreflections and fall-off included), and a file
    // measured on a target is usually the better: refused, unless the images contradict the file
    // itself (another order, another capture's), where the estimate is the one left standing.
    const std::string contradicted = io::DescribeIntensityFile(dataset);
    if (c.normals_moved_deg > 1 && contradicted.empty()) {
      throw std::runtime_error(
          std::string(text) +
          ": the images cannot tell which set is right, and intensities measured on a target are "
          "usually the better ones; nothing written. Run without --estimate-intensities to use "
          "the file's, or add --intensities none to use the estimate unchecked");
    } else if (c.normals_moved_deg > 1) {
      Warn(std::string(text) +
           ": the images contradict the file (said above), so the estimate is used; check the "
           "file against the images' order");
    } else {
      Say(o.common, "%s (compared in %.1f s)\n", text, c.seconds);
    }
    return out;
  }

  // No file. An estimate within its own error of equal lights does not show the lights to
  // differ, and equal lights are what a run without the flag uses: past a degree apart the data
  // cannot say the estimate is the better (a rendered bunny lit alike: estimate within 3.3 % of
  // equal, normals 4.10 deg off against 0.49). With --intensities none the user asked for the
  // estimate unchecked.
  double departure = 0;
  for (const Rgb& e : estimate.light_intensities) {
    departure = std::max(departure, (e.array() - 1).abs().maxCoeff());
  }
  const bool asked_unchecked = o.capture.options.intensities == io::kNoIntensities;
  if (!asked_unchecked && departure < calibrate::kEstimateLargestError) {
    const std::vector<Rgb> equal(estimate.light_intensities.size(), Rgb::Ones());
    const calibrate::IntensityComparison c = compare(equal);
    out.metrics["against_equal"] = figures(c);
    if (c.normals_moved_deg > 1) {
      char text[600];
      std::snprintf(
          text, sizeof text,
          "%s: --estimate-intensities: the estimated intensities are all within %.1f%% of equal "
          "lights, inside the estimate's own error where calibrated intensities were known (up "
          "to %.0f%%), yet they move the normals %.2f deg from equal intensities': the lights "
          "look alike and the photos cannot show the estimate is the better; nothing written. "
          "Run without --estimate-intensities (every light 1), calibrate the lights, or add "
          "--intensities none to use the estimate unchecked",
          o.dataset.c_str(), 100 * departure, 100 * calibrate::kEstimateLargestError,
          c.normals_moved_deg);
      throw std::runtime_error(text);
    }
  }
  // Nothing to check the estimate against, and no figure of the photos bounds its error: a
  // factor that varies smoothly with the light's direction (a fall-off or reflectance Lambert
  // does not model) is explained as well by intensities as by normals, so the user hears it.
  Warn(o.dataset +
       ": --estimate-intensities with no intensity file to check the estimate against: " +
       calibrate::kUncheckedEstimateNote +
       "; calibrate the lights (iphong calibrate-lights on a matte sphere) where a degree matters");
  return out;
}

}  // namespace iphong::cli
