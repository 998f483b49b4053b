// `iphong normals` on a capture larger than the memory limit: solve/bands.h over io::CaptureBands,
// every result written a band at a time (io::ImageRowWriter), so neither the observations nor the
// outputs are ever whole in memory.
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <vector>

#include "core/errors.h"
#include "core/parallel.h"
#include "core/timing.h"
#include "core/version.h"
#include "io/files.h"
#include "io/image_rows.h"
#include "io/visualize.h"
#include "iphong/console.h"
#include "iphong/normals_command.h"
#include "near/effective_distance.h"
#include "render/preview.h"
#include "solve/bands.h"
#include "solve/few_images.h"

namespace iphong::cli {
namespace {

// The process itself: OpenImageIO, Ceres, OpenCV and the C++ runtime, measured at about 140 MB
// of resident memory before the first image is read.
constexpr double kProcessBytes = 200e6;
// Per working pixel of a band beyond its observations: the fitted results (11 floats), the
// per-pixel solutions of the fit and the pictures' rows.
constexpr double kResultBytesPerPixel = 11 * 4 + 160 + 4 * 6;
// Bands never hold the whole ground truth, so they do not compare against it; the Read line and
// metrics.json say so in these words.
constexpr const char* kBandsGroundTruthNote =
    "not compared in bands, which never hold the whole ground truth: iphong eval normals.exr "
    "DATASET compares it";

// The rows of a band: the masked pixels of rows [y0, y1) of the working mask.
Mask BandMask(const Mask& mask, int y0, int y1) {
  Mask band(mask.width, y1 - y0, false);
  std::copy(mask.inside.begin() + static_cast<std::ptrdiff_t>(y0) * mask.width,
            mask.inside.begin() + static_cast<std::ptrdiff_t>(y1) * mask.width,
            band.inside.begin());
  return band;
}

}  // namespace

int NormalsMemory::BandRows(double limit, int height) const {
  const double room = limit - fixed_bytes;
  if (!(room >= per_row_bytes)) return 0;
  return static_cast<int>(std::min<double>(height, std::floor(room / per_row_bytes)));
}

NormalsMemory EstimateNormalsMemory(const io::CaptureBands& capture,
                                    const solve::NormalOptions& options, int threads) {
  const io::Dataset& d = capture.dataset();
  const double k = static_cast<double>(d.filenames.size());
  const double masked = static_cast<double>(d.mask.count());
  const double pixels = static_cast<double>(capture.width()) * capture.height();
  NormalsMemory m;
  // In memory (io::LoadObservations): the observations, a decoded image and the decoder's buffer
  // per thread, the results, the pictures, and the ground truth as MATLAB doubles.
  const double decoding = std::min<double>(ResolveThreads(threads), k) * 2.0 * d.file_width *
                          d.file_height * 4 * sizeof(float);
  m.whole_bytes = kProcessBytes + k * masked * 3 * sizeof(float) + decoding +
                  pixels * (kResultBytesPerPixel + 1) +
                  (d.files.ground_truth_path.empty() ? 0.0 : pixels * 3 * 8 * 2) +
                  (k < 3 ? masked * solve::kFewImageBytesPerPixel : 0.0);
  // In bands: the plan sample's observations stay for the whole run.
  const double sample = std::min<double>(masked, static_cast<double>(options.plan_sample));
  m.fixed_bytes = kProcessBytes + capture.FixedBytes() + sample * (k * 3 * sizeof(float) + 64);
  m.per_row_bytes = capture.BytesPerRow() + capture.width() * kResultBytesPerPixel;
  return m;
}

void RunNormalsInBands(const NormalsCommandOptions& o, io::OutputFolder& out,
                       io::CaptureBands& capture, int band_rows, const NormalsMemory& memory,
                       bool field, double started_seconds_ago) {
  const auto start = Clock::now();
  const io::Dataset& dataset = capture.dataset();
  const int k = static_cast<int>(dataset.filenames.size());
  const std::string too_big =
      o.dataset + ": in bands of rows (" + SizeText(capture.width(), capture.height()) + " x " +
      std::to_string(k) + " images would need " + FormatBytes(memory.whole_bytes) + " whole)";
  // Over the memory limit that is exit 3; with --band-rows asked for, the request is wrong.
  const auto refuse = [&](const std::string& why) {
    if (o.band_rows > 0) throw std::runtime_error(too_big + ": " + why);
    throw ResourceError(too_big + ": " + why);
  };
  if (k < 3) refuse("one or two images are solved whole, not in bands");
  if (o.estimate_intensities) refuse("--estimate-intensities needs the whole capture at once");
  if (o.integrate) {
    refuse(
        "--integrate needs the whole normal map: leave it out and run `iphong integrate` on "
        "normals.exr");
  }
  Say(o.common, "Read %s: %s\n", o.dataset.c_str(),
      io::DescribeDataset(dataset, kBandsGroundTruthNote).c_str());
  for (const std::string& warning : dataset.warnings) Warn(warning);
  Say(o.common,
      "In bands of %d rows: the whole capture would need %s (memory limit %s); each band needs "
      "about %s\n",
      band_rows, FormatBytes(memory.whole_bytes).c_str(),
      FormatBytes(static_cast<double>(o.common.memory().resolved())).c_str(),
      FormatBytes(memory.fixed_bytes + band_rows * memory.per_row_bytes).c_str());

  solve::NormalOptions options = NormalOptionsFor(o, dataset);
  const int width = capture.width(), height = capture.height();
  solve::BandSource source;
  source.width = width;
  source.height = height;
  source.masked_pixels = dataset.mask.count();
  // The light file's depth axis from every band of the first pass (a spread stride of its
  // pixels), as the in-memory run checks a spread sample of the whole capture.
  solve::DepthAxisCounts depth_counts;
  const std::size_t depth_stride = std::max<std::size_t>(1, (source.masked_pixels + 19999) / 20000);
  source.read = [&](int y0, int y1, bool first_pass) {
    solve::PhotometricData band = capture.ReadBand(y0, y1, first_pass);
    if (first_pass) depth_counts.Add(band, depth_stride);
    return band;
  };

  // The writers open on the first band, when the plan says which maps there are.
  std::unique_ptr<io::ImageRowWriter> normals, picture, albedo, residual, specular, model;
  std::vector<float> sample_albedo;  // every 64th solved pixel's brightest channel
  std::size_t specular_pixels = 0, chosen_pixels = 0;
  const bool directx = o.convention == "directx";
  auto progress = std::make_shared<Progress>("sample", o.common.progress_mode(), "rows", height);
  std::shared_ptr<Progress> fit;
  solve::BandProgress band_progress;
  int fit_pass = 0;
  band_progress.rows = [&](int pass, int rows) {
    if (pass >= 2 && pass != fit_pass) {  // the fit, then each near pass: a bar each
      progress.reset();
      fit.reset();
      fit_pass = pass;
      fit = std::make_shared<Progress>(pass == 2 ? "fit" : "near pass " + std::to_string(pass - 2),
                                       o.common.progress_mode(), "rows", height);
    }
    (pass == 1 ? progress : fit)->Count(rows);
  };
  // The encoding check on the plan sample, as the in-memory run makes it on the whole capture's
  // spread sample (the same pixels when the capture holds fewer than the plan sample).
  nlohmann::json encoding_check, depth_axis_check;
  band_progress.sample = [&](const solve::PhotometricData& sample) {
    if (encoding_check.is_null()) encoding_check = CheckEncoding(o, dataset, sample, options);
  };
  // The field averaged over f×f blocks for the light file's frame check: the whole capture's
  // normals are never in memory at once here.
  const int f = std::max(1, (std::max(width, height) + 255) / 256);
  integrate::NormalBlockAverage blocks(width, height, f);
  const auto write = [&](int y0, const solve::NormalResult& band) {
    const int rows = band.normals.height;
    {
      Mask solved = BandMask(dataset.mask, y0, y0 + rows);
      for (std::size_t p = 0; p < solved.inside.size(); ++p)
        solved.inside[p] = solved.inside[p] && band.residual.pixels[p] >= 0;
      blocks.AddRows(y0, band.normals, solved);
    }
    if (!normals) {
      normals = std::make_unique<io::ImageRowWriter>(out.file("normals.exr"), width, height, 3);
      picture = std::make_unique<io::ImageRowWriter>(out.file("normals.png"), width, height, 3,
                                                     io::WriteOptions{16, io::Encoding::kData});
      albedo = std::make_unique<io::ImageRowWriter>(out.file("albedo.exr"), width, height, 3);
      residual = std::make_unique<io::ImageRowWriter>(out.file("residual.exr"), width, height, 1);
      if (!options.material_known && !band.specular.pixels.empty()) {
        specular = std::make_unique<io::ImageRowWriter>(out.file("specular.exr"), width, height, 3);
      }
      if (!band.model_map.pixels.empty()) {
        model = std::make_unique<io::ImageRowWriter>(out.file("model.exr"), width, height, 1);
      }
    }
    const Mask mask = BandMask(dataset.mask, y0, y0 + rows);
    // Each file's rows are encoded side by side, the 16-bit picture (the slowest) first, as the
    // in-memory run writes its files; the next band is solved once all are written.
    std::vector<std::function<void()>> rows_of = {
        [&] { picture->WriteRows(io::NormalMapPicture(band.normals, mask, directx)); },
        [&] { normals->WriteRows(band.normals); }, [&] { albedo->WriteRows(band.albedo); },
        [&] { residual->WriteRows(band.residual); }};
    if (specular) rows_of.push_back([&] { specular->WriteRows(band.specular); });
    if (model) rows_of.push_back([&] { model->WriteRows(band.model_map); });
    RunTasks(rows_of, o.common.threads);
    if (model) {
      for (float v : band.model_map.pixels) {
        specular_pixels += v == 1;
        chosen_pixels += v >= 0;
      }
    }
    for (std::size_t p = 0; p < band.residual.pixels.size(); p += 64) {
      if (band.residual.pixels[p] < 0 || !mask.inside[p]) continue;
      const float* a = band.albedo.pixels.data() + 3 * p;
      sample_albedo.push_back(std::max({a[0], a[1], a[2]}));
    }
  };
  solve::NormalResult result;
  nlohmann::json effective_json;
  if (o.light_distance != "inf" && !field) {
    Warn(o.dataset +
         ": solved with distant lights: the effective light distance needs the whole "
         "normal map beside the bands (" +
         FormatBytes(memory.field_bytes) +
         "), more than the memory limit leaves; the in-memory run may choose a finite distance "
         "and differ (raise --memory-limit, or --light-distance inf to say so)");
  }
  try {
    if (field) {
      // The distant solve, the choice of D and the near passes, each pass over the bands; only
      // the per-pixel results are whole. Written when the last pass is done.
      near::EffectiveDistanceOptions e = EffectiveDistanceOptionsFor(o, options);
      const near::EffectiveDistanceResult r =
          near::SolveEffectiveDistanceInBands(source, band_rows, e, band_progress);
      if (o.light_distance != "inf") effective_json = EffectiveDistanceJson(r);
      for (int y0 = 0; y0 < height; y0 += band_rows) {
        write(y0, solve::ResultRows(r.normals, y0, std::min(height, y0 + band_rows)));
      }
      result = solve::ResultFields(r.normals);
      // The counts and timings of the distant solve in bands, and the passes' time.
      result.summary = r.distant.summary;
      for (const near::NearPass& pass : r.passes) result.summary.solve_seconds += pass.seconds;
    } else {
      result = solve::EstimateNormalsInBands(source, band_rows, options, write, band_progress);
    }
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(o.dataset + ": " + e.what());
  }
  // The counts are known once a pass has read every band; nothing is committed yet.
  if (std::string black = io::AllMaskedBlack(dataset); !black.empty()) {
    throw std::runtime_error(o.dataset + ": " + black);
  }
  fit.reset();
  progress.reset();
  std::optional<integrate::FrameCheckResult> frame;
  {
    ImageF small;
    Mask small_mask;
    blocks.Result(&small, &small_mask);
    depth_axis_check = ReportDepthAxis(o, dataset, dataset.light_directions,
                                       depth_counts.Result());  // --strict: throws
    if (!depth_axis_check.contains("warning")) {  // as in memory: no reading undoes that
      frame = CheckLightFrame(o, dataset, small, small_mask);  // --strict: throws
    }
  }
  {
    std::vector<std::function<void()>> finish;  // each file checked as written, side by side
    for (auto* w : {&picture, &normals, &albedo, &residual, &specular, &model})
      if (*w) finish.push_back([w] { (*w)->Finish(); });
    RunTasks(finish, o.common.threads);
  }

  // albedo.png from the albedo just written, scaled as WriteAlbedoPicture scales (its 99th
  // percentile to 0.8), the percentile taken over every 64th pixel.
  {
    ImageF brightest(static_cast<int>(sample_albedo.size()), 1, 1);
    brightest.pixels = sample_albedo;
    const float scale = sample_albedo.empty() ? 1.0f : render::AlbedoDisplayScale(brightest);
    io::ImageRowReader reader(out.file("albedo.exr"));
    io::ImageRowWriter pictures(out.file("albedo.png"), width, height, 3);
    for (int y0 = 0; y0 < height; y0 += band_rows) {
      const int y1 = std::min(height, y0 + band_rows);
      ImageF rows = reader.ReadRows(y0, y1);
      const Mask mask = BandMask(dataset.mask, y0, y1);
      for (std::size_t p = 0; p < mask.inside.size(); ++p)
        for (int c = 0; c < 3; ++c) rows.pixels[3 * p + c] *= mask.inside[p] ? scale : 0.0f;
      pictures.WriteRows(rows);
    }
    pictures.Finish();
  }

  nlohmann::json metrics;
  metrics["iphong_version"] = kVersion;
  metrics["dataset"] = o.dataset;
  metrics["input"] = NormalsInputJson(dataset);
  metrics["pixels"] = result.summary.pixels;
  metrics["images"] = k;
  if (frame) metrics["frame_check"] = FrameCheckJson(*frame);
  if (!encoding_check.is_null()) metrics["encoding_check"] = encoding_check;
  if (!depth_axis_check.is_null()) metrics["depth_axis_check"] = depth_axis_check;
  if (!effective_json.is_null()) metrics["effective_distance"] = effective_json;
  metrics["bands"] = {
      {"rows", band_rows},
      {"count", (height + band_rows - 1) / band_rows},
      {"memory_limit_bytes", o.common.memory().resolved()},
      {"estimated_whole_bytes", memory.whole_bytes},
      {"estimated_band_bytes", memory.fixed_bytes + band_rows * memory.per_row_bytes},
      {"estimated_row_bytes", memory.per_row_bytes},
      // The effective light distance's whole-field part (in the band figure when sought).
      {"effective_distance_bytes", memory.field_bytes},
      {"effective_distance_sought", field && o.light_distance != "inf"}};
  metrics["sample_seconds"] = result.summary.init_seconds;
  metrics.update(SolveMetricsJson(options, result, specular_pixels, chosen_pixels));
  if (!dataset.files.ground_truth_path.empty()) {
    metrics["ground_truth_note"] = kBandsGroundTruthNote;
  }
  if (result.material_estimated) {
    io::WriteTextFile(out.file("material.json"), EstimatedMaterialJson(result).dump(2) + "\n");
  }
  metrics["total_seconds"] = started_seconds_ago + SecondsSince(start);
  io::WriteTextFile(out.file("metrics.json"), metrics.dump(2) + "\n");
  out.Commit();
  PrintJson(o.common, metrics.dump(2));
  if (std::string counts = io::DescribeImageCounts(dataset); !counts.empty()) Warn(counts);
  Say(o.common,
      "%zu pixels x %d images in %d bands of %d rows, model %s: plan sample %.2f s, model "
      "choice %.2f s, search and fit %.2f s\n",
      result.summary.pixels, k, (height + band_rows - 1) / band_rows, band_rows,
      reflectance::LobeName(result.model).c_str(), result.summary.init_seconds,
      result.summary.model_seconds, result.summary.solve_seconds);
  SayModelAndFlags(o.common, result);
  Say(o.common, "Wrote %s: normals.exr/.png, albedo.exr/.png, residual.exr, metrics.json%s%s%s\n",
      o.output_dir.c_str(), result.material_estimated ? ", material.json" : "",
      specular ? ", specular.exr" : "", model ? ", model.exr" : "");
}

}  // namespace iphong::cli
