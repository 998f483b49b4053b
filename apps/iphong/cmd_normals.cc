// `iphong normals DATASET -o DIR`: per-pixel normals and albedo by inverting the Phong model;
// with ground truth, the angular errors (`iphong eval`, cmd_eval.cc: the same for any map).
#include <cstdio>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>

#include "calibrate/lights.h"
#include "core/errors.h"
#include "core/parallel.h"
#include "core/timing.h"
#include "core/version.h"
#include "integrate/frame_check.h"
#include "integrate/integrate.h"
#include "io/dataset.h"
#include "io/dataset_text.h"
#include "io/files.h"
#include "io/image_io.h"
#include "io/output_folder.h"
#include "io/surface.h"
#include "io/visualize.h"
#include "iphong/commands.h"
#include "iphong/console.h"
#include "iphong/normals_command.h"
#include "solve/image_check.h"
#include "solve/metrics.h"
#include "solve/normals.h"

namespace iphong::cli {

namespace {

// The capture's headers and mask first: when its observations and results would not fit in the
// memory limit (or --band-rows asks), it is solved in bands of rows instead, with the same result,
// and true returned.
bool SolvedInBands(const NormalsCommandOptions& o, io::OutputFolder& out,
                   Clock::time_point total_start) {
  io::DatasetLoadOptions load;
  load.capture = o.capture.resolved();
  load.threads = o.common.threads;
  load.memory = o.common.memory();
  io::CaptureBands capture(o.dataset, load);
  NormalsMemory memory =
      EstimateNormalsMemory(capture, NormalOptionsFor(o, capture.dataset()), o.common.threads);
  // The effective light distance's whole-field part (the surface, two passes' results), in
  // memory as in bands; with --light-distance inf too, for the foil's refit at D = ∞.
  const bool sought =
      capture.dataset().filenames.size() >= 3 && !capture.dataset().files.near.present();
  if (sought) {
    memory.field_bytes =
        static_cast<double>(capture.dataset().mask.count()) * near::kEffectiveDistanceBytesPerPixel;
    memory.whole_bytes += memory.field_bytes;
  }
  const double limit = static_cast<double>(load.memory.resolved());
  if ((memory.whole_bytes > limit || o.band_rows > 0) && capture.dataset().files.near.present()) {
    throw ResourceError(o.dataset +
                        ": a near-light capture is solved whole (its surface "
                        "places every pixel's lights): it needs " +
                        FormatBytes(memory.whole_bytes) + ", more than the memory limit of " +
                        FormatBytes(limit) + (o.band_rows > 0 ? " (--band-rows)" : ""));
  }
  if (memory.whole_bytes > limit || o.band_rows > 0) {
    // In bands the whole-field part sits beside the bands, when it leaves room for a row.
    NormalsMemory banded = memory;
    bool field = sought;
    if (field) {
      banded.fixed_bytes += banded.field_bytes;
      if (banded.BandRows(limit, capture.height()) < 1 &&
          memory.BandRows(limit, capture.height()) >= 1) {
        field = false;
        banded.fixed_bytes = memory.fixed_bytes;
      }
    }
    const int rows = o.band_rows > 0 ? std::min(o.band_rows, capture.height())
                                     : banded.BandRows(limit, capture.height());
    if (rows < 1) {
      throw ResourceError(o.dataset + ": one row of " + SizeText(capture.width(), 1) + " x " +
                          std::to_string(capture.dataset().filenames.size()) + " images needs " +
                          FormatBytes(banded.fixed_bytes + banded.per_row_bytes) +
                          ", more than the memory limit of " + FormatBytes(limit) +
                          " (raise it with --memory-limit)");
    }
    RunNormalsInBands(o, out, capture, rows, banded, field, SecondsSince(total_start));
    return true;
  }
  return false;
}

void RunNormals(const NormalsCommandOptions& o) {
  const auto total_start = Clock::now();
  RequireFolder(o.dataset);
  // The output folder is checked first: a refusal costs nothing.
  io::OutputFolderOptions folder;
  folder.command = "normals";
  folder.overwrite = o.common.overwrite;
  // Every file the run reads: the folder, and what the capture flags name outside it.
  folder.inputs = {o.dataset, o.capture.options.images, o.capture.options.lights,
                   o.capture.options.intensities, o.capture.options.mask};
  io::OutputFolder out(o.output_dir, folder);
  if (SolvedInBands(o, out, total_start)) return;
  io::ObservationSet loaded = LoadCaptureObservations(o.dataset, o.capture, o.common);
  io::Dataset& dataset = loaded.dataset;
  ReportCapture(o.dataset, dataset, o.common);
  if (std::string black = io::AllMaskedBlack(dataset); !black.empty()) {
    throw std::runtime_error(o.dataset + ": " + black);
  }
  solve::NormalOptions options = NormalOptionsFor(o, dataset);
  auto fit_progress = std::make_shared<Progress>("fit", o.common.progress_mode());
  options.progress = [fit_progress](double fraction) { fit_progress->Update(fraction); };

  const double load_seconds = SecondsSince(total_start);
  std::optional<EstimatedIntensities> estimated;
  if (o.estimate_intensities) {
    estimated = EstimateCheckedIntensities(o, dataset, loaded.observations);
    loaded.observations.light_intensities = estimated->estimate.light_intensities;
  }
  const solve::PhotometricData& data = loaded.observations;  // masked pixels only
  const nlohmann::json encoding_check = CheckEncoding(o, dataset, data, options);
  const nlohmann::json depth_axis_check = CheckDepthAxis(o, dataset, data);

  // One or two images: the per-pixel problem is ambiguous and the library solves it globally
  // with priors, which needs the coefficients, kd included.
  if (data.images < 3 && (!dataset.material || !dataset.material->kd_known || o.ignore_material)) {
    throw std::runtime_error(o.dataset + "/material.json: with " + std::to_string(data.images) +
                             " image(s) the coefficients must be known, kd (a uniform albedo) "
                             "included");
  }
  std::optional<NearRun> near_run;
  if (dataset.files.near.present()) {
    near_run = SolveNearCapture(o, dataset, data, options);
  } else if (o.distance > 0) {
    throw std::runtime_error(o.dataset + ": --distance is for near-light captures (" +
                             "light_positions.txt and camera.json)");
  }
  nlohmann::json metrics;
  std::optional<near::EffectiveDistanceResult> effective;
  if (!near_run && data.images >= 3) {
    effective = estimated && estimated->run
                    ? SolveWithEffectiveDistance(o, data, options, metrics,
                                                 std::move(estimated->run), estimated->run_log)
                    : SolveWithEffectiveDistance(o, data, options, metrics);
  }
  const solve::NormalResult result = near_run    ? near_run->result.normals
                                     : effective ? effective->normals
                                                 : solve::RecoverNormals(data, options);
  options.progress = nullptr;
  fit_progress.reset();  // clears its line
  const ImageF& ambiguity = result.ambiguity_deg;
  // The light file's frame, from the normals it gave (CheckLightFrame). The one- and two-image
  // solve is left out: its priors make any reading integrable.
  std::optional<integrate::FrameCheckResult> frame;
  // A file whose depth axis is another has had its warning: no reading of the image plane
  // undoes that, and the normals the search kept on the camera's side say nothing of one.
  const bool depth_slip = depth_axis_check.contains("warning");
  if (ambiguity.pixels.empty() && !near_run && !depth_slip) {
    Mask with_normal = dataset.mask;
    for (std::size_t p = 0; p < with_normal.inside.size(); ++p)
      with_normal.inside[p] = with_normal.inside[p] && result.residual.pixels[p] >= 0;
    frame = CheckLightFrame(o, dataset, result.normals, with_normal);
  }

  // The images against a render of the result with the lights it was solved under: the near
  // run's point lights from its surface, or directions only and the distant solve.
  const nlohmann::json image_check =
      near_run
          ? CheckImagesAgree(
                o, dataset,
                NearRunData(dataset, data, *near_run, solve::ImageCheckOptions{}.sample), result,
                options)
          : CheckImagesAgree(o, dataset, data, effective ? effective->distant : result, options);

  metrics["iphong_version"] = kVersion;
  metrics["dataset"] = o.dataset;
  metrics["input"] = NormalsInputJson(dataset);
  metrics["pixels"] = data.pixel_count();
  metrics["images"] = data.images;
  std::size_t specular_pixels = 0, chosen_pixels = 0;
  for (float v : result.model_map.pixels) {
    specular_pixels += v == 1;
    chosen_pixels += v >= 0;
  }
  metrics.update(SolveMetricsJson(options, result, specular_pixels, chosen_pixels));
  metrics["load_seconds"] = load_seconds;
  metrics["init_seconds"] = result.summary.init_seconds;
  if (!ambiguity.pixels.empty()) {
    metrics["solver"] = "global (one or two images): data + smoothness + integrability + boundary";
  }
  if (estimated) metrics["estimated_intensities"] = estimated->metrics;
  if (frame) metrics["frame_check"] = FrameCheckJson(*frame);
  if (!encoding_check.is_null()) metrics["encoding_check"] = encoding_check;
  if (!depth_axis_check.is_null()) metrics["depth_axis_check"] = depth_axis_check;
  if (!image_check.is_null()) metrics["image_check"] = image_check;
  std::optional<solve::AngularErrorMetrics> errors;
  if (!dataset.normal_gt.pixels.empty()) {
    try {
      errors = solve::CompareNormals(result.normals, dataset.normal_gt, dataset.mask);
      metrics.update(AngularErrorJson(*errors));
    } catch (const std::invalid_argument& e) {
      // The normals stand without it: a ground truth that is zero wherever they were solved
      // (another object's, or every pixel flagged) is named, not a reason to discard them.
      Warn(dataset.files.ground_truth_path + ": not compared: " + e.what());
      metrics["ground_truth_note"] = std::string("not compared: ") + e.what();
    }
  }

  // The images and pictures are encoded side by side (each file alone: the same bytes as one
  // after another), the largest first; the first failure, in this order, is reported. An encoder
  // per thread holds less than the decoders EstimateNormalsMemory allowed for, freed by now.
  std::vector<std::function<void()>> writes;
  const auto write = [&](const std::string& name, auto how) {
    writes.push_back([how = std::move(how), path = out.file(name)] { how(path); });
  };
  write("normals.exr", [&](const std::string& path) { io::WriteImage(path, result.normals); });
  write("albedo.exr", [&](const std::string& path) { io::WriteImage(path, result.albedo); });
  write("normals.png", [&](const std::string& path) {
    io::WriteImage(path,
                   io::NormalMapPicture(result.normals, dataset.mask, o.convention == "directx"),
                   {16, io::Encoding::kData});
  });
  write("residual.exr", [&](const std::string& path) { io::WriteImage(path, result.residual); });
  const bool specular_map = result.material_estimated && !result.specular.pixels.empty();
  if (specular_map) {
    write("specular.exr", [&](const std::string& path) { io::WriteImage(path, result.specular); });
  }
  if (!ambiguity.pixels.empty()) {
    write("ambiguity.exr", [&](const std::string& path) { io::WriteImage(path, ambiguity); });
  }
  if (!result.model_map.pixels.empty()) {
    write("model.exr", [&](const std::string& path) { io::WriteImage(path, result.model_map); });
  }
  write("albedo.png", [&](const std::string& path) {
    io::WriteAlbedoPicture(path, result.albedo, dataset.mask);
  });
  write("residual.png", [&](const std::string& path) {
    Mask fitted = dataset.mask;  // residual −1: flagged pixels, black in the picture
    for (std::size_t p = 0; p < fitted.inside.size(); ++p)
      fitted.inside[p] = fitted.inside[p] && result.residual.pixels[p] >= 0;
    io::WriteErrorMap(path, result.residual, fitted, io::ErrorMapScale(result.residual, fitted),
                      "rms");
  });
  if (errors) {
    write("error.png", [&](const std::string& path) {
      io::WriteErrorMap(
          path, errors->error_deg, dataset.mask,
          o.error_range > 0 ? o.error_range : io::ErrorMapScale(errors->error_deg, dataset.mask));
    });
  }
  RunTasks(writes, o.common.threads);
  if (result.material_estimated) {
    io::WriteTextFile(out.file("material.json"), EstimatedMaterialJson(result).dump(2) + "\n");
  }
  if (estimated) {
    io::WriteTextFile(out.file("light_intensities.txt"),
                      io::FormatTriples(estimated->estimate.light_intensities));
  }
  if (near_run) WriteNearOutputs(out, *near_run, dataset, metrics, o.common);
  std::optional<io::SurfaceFiles> surface;
  integrate::IntegrateResult heights;
  if (o.integrate && !near_run) {
    // Pixels the solver flagged (residual −1: dark everywhere or too few lights) carry a
    // placeholder normal and are left out; silhouette normals may tip slightly past 90°.
    Mask with_normal = dataset.mask;
    for (std::size_t p = 0; p < with_normal.inside.size(); ++p) {
      if (result.residual.pixels[p] < 0) with_normal.inside[p] = 0;
    }
    integrate::IntegrateOptions integration;
    integration.allow_back_facing = true;
    integration.threads = o.common.threads;
    auto integrate_progress = std::make_shared<Progress>("integrate", o.common.progress_mode());
    integration.progress = [integrate_progress](double f) { integrate_progress->Update(f); };
    RequireMemory(
        o.common.memory(), io::EstimateSurfaceBytes(with_normal.count(), integration),
        o.dataset + ": integrating and meshing " + std::to_string(with_normal.count()) + " pixels");
    heights = integrate::IntegrateNormals(result.normals, with_normal, integration);
    io::SurfaceFileOptions files;
    files.albedo = &result.albedo;
    files.threads = o.common.threads;
    surface = io::WriteSurfaceFiles(out, "", heights, result.normals, with_normal,
                                    io::FrameOf(integration), files);
    metrics["integrate_seconds"] = heights.summary.total_seconds;
  }
  metrics["total_seconds"] = SecondsSince(total_start);
  io::WriteTextFile(out.file("metrics.json"), metrics.dump(2) + "\n");
  out.Commit();
  PrintJson(o.common, metrics.dump(2));

  if (near_run) {
    Say(o.common, "%zu pixels x %d images, model %s: load %.2f s, near-light loop %.2f s\n",
        data.pixel_count(), data.images, reflectance::LobeName(result.model).c_str(), load_seconds,
        near_run->result.seconds);
  } else if (ambiguity.pixels.empty()) {
    Say(o.common,
        "%zu pixels x %d images, model %s: load %.2f s, Woodham %.2f s, model choice %.2f s, "
        "search and fit %.2f s\n",
        data.pixel_count(), data.images, reflectance::LobeName(result.model).c_str(), load_seconds,
        result.summary.init_seconds, result.summary.model_seconds, result.summary.solve_seconds);
  } else {
    Say(o.common,
        "%zu pixels x %d images, model %s: load %.2f s, global solve with priors %.2f s "
        "(%lld iterations)\n",
        data.pixel_count(), data.images, reflectance::LobeName(options.model).c_str(), load_seconds,
        result.summary.solve_seconds, result.summary.iterations);
  }
  SayModelAndFlags(o.common, result);
  if (near_run) {
    const near::NearResult& r = near_run->result;
    char depth[96] = "";
    if (metrics["near_lights"].contains("depth_rmse_mm")) {
      std::snprintf(depth, sizeof depth, ", depth RMSE %.3g mm against Depth_gt.mat",
                    metrics["near_lights"]["depth_rmse_mm"].get<double>());
    }
    Say(o.common, "Near lights: %zu passes (%s), the object %.4g mm from the camera%s\n",
        r.passes.size(), r.converged ? "the normals settled" : "stopped before they settled",
        r.distance, depth);
  }
  if (errors) {
    Say(o.common,
        "Angular error against the ground truth: mean %.2f deg, median %.2f deg "
        "(< 5 deg: %.0f%%, < 10 deg: %.0f%%, < 20 deg: %.0f%%)\n",
        errors->mean_deg, errors->median_deg, 100 * errors->below_5_deg, 100 * errors->below_10_deg,
        100 * errors->below_20_deg);
  }
  if (surface) {
    Say(o.common,
        "Integrated heights (%s, %.3f s): surface normals vs recovered: mean %.2f deg; "
        "mesh %zu triangles\n",
        integrate::MethodName(heights.summary.method), heights.summary.total_seconds,
        surface->consistency_mean_deg, surface->triangles);
  }
  Say(o.common,
      "Wrote %s: normals.exr/.png, albedo.exr/.png, residual.exr/.png, "
      "metrics.json%s%s%s%s%s%s%s\n",
      o.output_dir.c_str(), estimated ? ", light_intensities.txt" : "",
      result.material_estimated ? ", material.json" : "", specular_map ? ", specular.exr" : "",
      errors ? ", error.png" : "", ambiguity.pixels.empty() ? "" : ", ambiguity.exr",
      result.model_map.pixels.empty() ? "" : ", model.exr",
      surface || near_run ? ", height.exr, mesh.ply, height.png, integrate.json" : "");
  if (near_run) Say(o.common, "  and depth.exr (mm along the optical axis), the mesh in mm\n");
}

}  // namespace

void AddNormalsCommand(CLI::App& app) {
  auto o = std::make_shared<NormalsCommandOptions>();
  auto* cmd = app.add_subcommand(
      "normals",
      "Recover normals and albedo from a capture folder (DiLiGenT, UW, RTI .lp, images + lights)");
  cmd->add_option("dataset", o->dataset,
                  "Capture folder: DiLiGenT, UW, RTI .lp, or a folder of images with a light file")
      ->required();
  cmd->add_option("-o,--output", o->output_dir,
                  "Output folder: new or empty, or an earlier normals output with --overwrite")
      ->required();
  cmd->add_option(
         "--model", o->model,
         "Reflectance model (default: material.json's, else chosen by held-out prediction)")
      ->check(CLI::IsMember({"phong", "blinn-phong", "lambert", "oren-nayar", "normal-centred"}));
  cmd->add_flag("--ignore-material", o->ignore_material,
                "Ignore material.json: choose the model and estimate ks per pixel");
  cmd->add_option("--discard-dark", o->discard_dark,
                  "Fraction of each pixel's darkest observations Woodham drops")
      ->check(CLI::Range(0.0, 0.9))
      ->capture_default_str();
  cmd->add_option("--discard-bright", o->discard_bright,
                  "Fraction of each pixel's brightest observations Woodham drops")
      ->check(CLI::Range(0.0, 0.9))
      ->capture_default_str();
  cmd->add_option("--normal-map-convention", o->convention, "normals.png green axis")
      ->check(CLI::IsMember({"opengl", "directx"}))
      ->capture_default_str();
  cmd->add_option("--shadow-threshold", o->shadow_threshold,
                  "Observations darker than the model by more than this fraction of the pixel's "
                  "brightness count as shadowed (censored)")
      ->check(Positive())
      ->capture_default_str();
  cmd->add_option("--irls-rounds", o->irls_rounds, "Censoring rounds of the local fit")
      ->check(CLI::Range(1, 20))
      ->capture_default_str();
  cmd->add_flag("--uniform-weights", o->uniform_weights,
                "Weigh every observation alike (by default a band of oblique lights whose held-out "
                "misfit is biased is weighed down and the bias left taken off)");
  cmd->add_flag("!--no-pixel-test", o->pixel_test,
                "Skip each pixel's held-out test of Lambert against the object's model (every "
                "pixel takes the object's model, its ks fitted per pixel; no model.exr): under 24 "
                "lights or fewer, where the test holds out one light at a time, it is most of the "
                "solve (docs/benchmarks.md has the time and accuracy it trades)");
  cmd->add_flag("--fast", o->fast,
                "Fit normals to the luminance instead of all three channels (about 2x faster)");
  cmd->add_flag("--estimate-intensities", o->estimate_intensities,
                "Estimate each light's RGB intensity with the normals (semi-calibrated; an "
                "intensity file is not used for the normals, only compared with: how far apart "
                "the two runs' normals are is said, and past a degree the run is refused unless "
                "the images contradict the file; with --intensities none, or no file, a warning "
                "says the estimate is unchecked; written as light_intensities.txt, each "
                "channel's mean 1)");
  cmd->add_option("--error-range", o->error_range,
                  "With ground truth: degrees at the top of error.png's colour scale, so maps of "
                  "several runs compare (default: from the data, the 95th percentile rounded up)")
      ->check(Positive());
  cmd->add_flag("--strict", o->strict,
                "Refuse (exit 1, nothing written) a light file whose normals read better in "
                "another frame (y down, x mirrored, x and y swapped) instead of warning");
  cmd->add_option("--band-rows", o->band_rows,
                  "Read and solve the capture in bands of this many rows (default: only when it "
                  "does not fit in --memory-limit, in bands that do; the result is the same)")
      ->check(CLI::Range(1, 1 << 30));
  cmd->add_flag("--integrate", o->integrate,
                "Also integrate the normals: height.exr, mesh.ply (albedo colours), height.png "
                "(near-light captures always: in mm)");
  cmd->add_option("--light-distance", o->light_distance,
                  "Captures with light directions only: how far the lights are, in pixels of the "
                  "images — auto (chosen by held-out prediction, distant lights among the "
                  "candidates), inf (distant), or a number")
      ->capture_default_str();
  cmd->add_option("--distance", o->distance,
                  "Near-light captures: the object's distance from the camera along its axis, "
                  "mm, a first guess (default: from the lights' layout, else from the images)")
      ->check(Scale());
  AddCaptureOptions(cmd, o->capture);
  AddOverwriteOption(cmd, o->common);
  AddThreadsOption(cmd, o->common);
  AddMemoryOption(cmd, o->common);
  AddReportOptions(cmd, o->common);
  cmd->callback([o] { RunNormals(*o); });
}

}  // namespace iphong::cli
