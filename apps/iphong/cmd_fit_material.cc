// `iphong fit-material DATASET --normals N -o DIR`: the material's coefficients with standard
// errors, the model chosen by held-out lights, and pictures of the fit.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "calibrate/lights.h"
#include "core/timing.h"
#include "core/version.h"
#include "io/dataset.h"
#include "io/files.h"
#include "io/image_io.h"
#include "io/material_pictures.h"
#include "io/near_capture.h"
#include "io/output_folder.h"
#include "io/visualize.h"
#include "iphong/commands.h"
#include "iphong/console.h"
#include "material/fit.h"

namespace iphong::cli {
namespace {

struct FitMaterialCommandOptions {
  std::string dataset;
  std::string normals;
  bool sphere = false;
  std::string output_dir;
  std::vector<std::string> models;
  std::string albedo = "per-pixel";
  std::string regions;  // a label image: one kd per distinct value
  int folds = material::MaterialFitOptions{}.folds;
  int max_pixels = material::MaterialFitOptions{}.max_pixels;
  double saturation = material::MaterialFitOptions{}.saturation;
  double shadow_threshold = material::MaterialFitOptions{}.shadow_threshold;
  CaptureFlags capture;
  CommonOptions common;
};

// The fit takes every light as distant, seen from the object's centre. Under near lights that
// bends the coefficients (a broad lobe and a wrong kd imitate the irradiance's fall-off), so say
// how near they are, as calibrate-lights does: how far their directions turn across the object
// (2·asin(r/d), r half the mask's larger side at the layout's distance), warned from a degree on.
void WarnNearLights(const io::Dataset& dataset, const solve::PhotometricData& data) {
  const io::NearLightFiles& near = dataset.files.near;
  if (!near.present() || data.pixels.empty()) return;
  const double distance = io::LayoutDistanceMm(near);
  const geometry::HeightMapFrame frame = near.frame();
  const double value = frame.perspective ? distance : -distance;
  Vec3d lo = Vec3d::Constant(HUGE_VAL), hi = -lo;
  for (int p : data.pixels) {
    const Vec3d x = geometry::HeightMapPoint(frame, data.width, data.height, p % data.width,
                                             p / data.width, value);
    lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  }
  const Vec3d centre = 0.5 * (lo + hi);
  const double radius = 0.5 * (hi - lo).head<2>().maxCoeff();
  double worst = 0, nearest = HUGE_VAL;
  for (const Vec3d& s : near.positions_mm) {
    const double d = (s - centre).norm();
    nearest = std::min(nearest, d);
    worst = std::max(worst, 2 * std::asin(std::min(1.0, radius / std::max(d, 1e-12))) * 180 / M_PI);
  }
  if (worst < 1) return;
  char text[400];
  std::snprintf(text, sizeof text,
                ": the lights are point lights, the nearest %.3g object sizes away: their "
                "directions turn by up to %.2g deg across the object, and fit-material takes them "
                "as distant (seen from its centre), so the coefficients absorb their fall-off; fit "
                "a capture with distant lights for a material to trust",
                nearest / (2 * radius), worst);
  Warn(near.positions_path + text);
}

// JSON has no NaN: a standard error that does not exist is null.
nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }
nlohmann::json Triple(const Vec3d& v) { return {Number(v[0]), Number(v[1]), Number(v[2])}; }

// The normals for the dataset's pixels, and where they came from: a normal map (EXR, PNG,
// Normal_gt.mat), an `iphong normals` or `fit-material` output folder (its normals.exr), the
// dataset folder itself (its ground truth), or the sphere fitted to the mask.
ImageF LoadNormals(const FitMaterialCommandOptions& o, const io::Dataset& dataset,
                   std::string* source) {
  const int w = dataset.width(), h = dataset.height();
  if (o.sphere) {
    if (dataset.files.mask_path.empty()) {
      throw std::runtime_error(o.dataset +
                               ": --sphere fits the sphere to the mask, and there is none "
                               "(mask.png, or --mask)");
    }
    std::vector<std::string> warnings;
    std::vector<calibrate::SphereOutline> outlines;
    try {
      outlines = calibrate::FindSpheres(dataset.mask, calibrate::SphereSearch{}, &warnings);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(dataset.files.mask_path + ": " + e.what());
    }
    for (const std::string& warning : warnings) Warn(dataset.files.mask_path + ": " + warning);
    const calibrate::SphereGeometry sphere =
        calibrate::SphereFromOutline(outlines.front(), calibrate::Intrinsics{});
    Mask on_sphere;
    ImageF normals = calibrate::SphereNormalMap({sphere}, w, h, &on_sphere);
    char text[160];
    std::snprintf(text, sizeof text, "the sphere fitted to %s (centre %.1f, %.1f, radius %.1f px)",
                  dataset.files.mask_path.c_str(), outlines.front().center_x_px,
                  outlines.front().center_y_px, outlines.front().radius_px);
    *source = text;
    return normals;
  }
  std::string path = o.normals;
  ImageF normals;
  if (std::filesystem::is_directory(path)) {
    if (std::filesystem::exists(path + "/normals.exr")) {
      path += "/normals.exr";
    } else if (std::error_code ec; std::filesystem::equivalent(path, o.dataset, ec)) {
      // The capture's own ground truth, read with it (and cropped and scaled as it was).
      if (dataset.normal_gt.pixels.empty()) {
        throw std::runtime_error(path +
                                 ": no normals.exr and no ground truth (Normal_gt.mat or "
                                 "normal.txt)");
      }
      *source = dataset.files.ground_truth_path;
      normals = dataset.normal_gt;
    } else {
      io::DatasetLoadOptions load;
      load.capture = o.capture.resolved();
      load.capture.lights_needed = false;
      load.load_images = false;
      load.memory = o.common.memory();
      io::Dataset d = io::LoadDataset(path, load);
      if (d.normal_gt.pixels.empty()) {
        throw std::runtime_error(path +
                                 ": no normals.exr and no ground truth (Normal_gt.mat or "
                                 "normal.txt)");
      }
      *source = d.files.ground_truth_path;
      normals = std::move(d.normal_gt);
    }
  }
  if (normals.pixels.empty()) {
    normals = io::ReadNormalMap(path, false, nullptr, o.common.memory());
    *source = path;
  }
  if (normals.width != w || normals.height != h) {
    throw std::runtime_error(*source + ": is " + SizeText(normals.width, normals.height) +
                             ", the images are " + SizeText(w, h));
  }
  return normals;
}

nlohmann::json ModelJson(const material::ModelFit& m, bool per_group_kd) {
  nlohmann::json j = {{"model", reflectance::LobeName(m.lobe)},
                      {"ambient_term", Triple(m.ambient_term)},
                      {"ambient_term_se", Triple(m.ambient_se)},
                      {"ambient_term_robust_se", Triple(m.ambient_robust_se)},
                      {"rss", m.rss},
                      {"sigma", Number(m.sigma)},
                      {"observations", m.observations},
                      {"parameters", m.parameters},
                      {"bic", Number(m.bic)},
                      {"heldout_rmse", Number(m.heldout_rmse)},
                      {"heldout_rmse_over_noise", Number(m.heldout_ratio)},
                      {"heldout_observations", m.heldout_observations},
                      {"iterations", m.iterations},
                      {"converged", m.converged}};
  if (m.lobe != reflectance::Lobe::kLambert) {
    j["ks"] = Triple(m.ks);
    j["ks_se"] = Triple(m.ks_se);
    j["ks_robust_se"] = Triple(m.ks_robust_se);
    j["shininess"] = m.shininess;
    j["shininess_se"] = Number(m.shininess_se);
    j["shininess_robust_se"] = Number(m.shininess_robust_se);
    j["ks_shininess_correlation"] = Triple(m.ks_shininess_correlation);
  }
  if (per_group_kd) {
    nlohmann::json kd = nlohmann::json::array(), se = nlohmann::json::array();
    for (std::size_t g = 0; g < m.kd.size(); ++g) {
      kd.push_back(Triple(m.kd[g]));
      se.push_back(g < m.kd_se.size() ? Triple(m.kd_se[g]) : nlohmann::json());
    }
    j["kd"] = kd;
    j["kd_se"] = se;
  }
  return j;
}

// "v ± se (robust ± r)": the model-based standard error and the sandwich one.
std::string WithError(double v, double se, double robust, const char* format) {
  char text[64], err[32] = "", rob[40] = "";
  std::snprintf(text, sizeof text, format, v);
  if (std::isfinite(se)) std::snprintf(err, sizeof err, " ± %.2g", se);
  if (std::isfinite(robust)) std::snprintf(rob, sizeof rob, " (robust ± %.2g)", robust);
  return std::string(text) + err + rob;
}

void RunFitMaterial(const FitMaterialCommandOptions& o) {
  const auto start = Clock::now();
  RequireFolder(o.dataset);
  if (o.sphere == !o.normals.empty()) {
    throw CLI::ValidationError("--normals", "give the geometry: --normals N or --sphere");
  }
  material::MaterialFitOptions options;
  if (!o.models.empty()) {
    options.models.clear();
    for (const std::string& m : o.models) options.models.push_back(reflectance::ParseLobe(m));
  }
  options.albedo = !o.regions.empty()      ? material::AlbedoMode::kPerRegion
                   : o.albedo == "uniform" ? material::AlbedoMode::kUniform
                                           : material::AlbedoMode::kPerPixel;
  options.folds = o.folds;
  options.max_pixels = o.max_pixels;
  options.saturation = o.saturation;
  options.shadow_threshold = o.shadow_threshold;
  options.threads = o.common.threads;
  if (std::string m = options.Validate(); !m.empty()) throw CLI::ValidationError("fit", m);

  io::OutputFolderOptions folder;
  folder.command = "fit-material";
  folder.overwrite = o.common.overwrite;
  folder.inputs = {o.dataset,
                   o.normals,
                   o.regions,
                   o.capture.options.images,
                   o.capture.options.lights,
                   o.capture.options.intensities,
                   o.capture.options.mask};
  io::OutputFolder out(o.output_dir, folder);

  const io::ObservationSet loaded = LoadCaptureObservations(o.dataset, o.capture, o.common);
  const io::Dataset& dataset = loaded.dataset;
  const solve::PhotometricData& data = loaded.observations;
  if (std::string m = material::CheckLightCount(data.images, options); !m.empty()) {
    throw std::runtime_error(o.dataset + ": " + m);
  }
  ReportCapture(o.dataset, dataset, o.common);
  WarnNearLights(dataset, data);

  std::string normals_source;
  const ImageF normal_map = LoadNormals(o, dataset, &normals_source);
  for (const std::string& w : io::CheckNormalMap(normal_map, &dataset.mask, normals_source))
    Warn(w);
  std::vector<Vec3d> normals(data.pixel_count());
  for (std::size_t p = 0; p < data.pixel_count(); ++p) {
    const float* n = normal_map.pixels.data() + 3 * std::size_t(data.pixels[p]);
    normals[p] = Vec3d(n[0], n[1], n[2]);
  }
  Say(o.common, "Normals: %s\n", normals_source.c_str());

  // Regions: each distinct value of the label image's first channel (0: left out), in order.
  std::vector<float> region_values;
  if (!o.regions.empty()) {
    const ImageF labels = io::ReadImage(o.regions, o.common.memory());
    if (labels.width != data.width || labels.height != data.height) {
      throw std::runtime_error(o.regions + ": is " + SizeText(labels.width, labels.height) +
                               ", the images are " + SizeText(data.width, data.height));
    }
    for (int p : data.pixels) {
      const float v = labels.pixels[std::size_t(p) * labels.channels];
      if (v > 0) region_values.push_back(v);
    }
    std::sort(region_values.begin(), region_values.end());
    region_values.erase(std::unique(region_values.begin(), region_values.end()),
                        region_values.end());
    if (region_values.empty()) {
      throw std::runtime_error(o.regions + ": no region inside the mask (every label is 0)");
    }
    for (int p : data.pixels) {
      const float v = labels.pixels[std::size_t(p) * labels.channels];
      options.region.push_back(
          v > 0 ? static_cast<int>(std::lower_bound(region_values.begin(), region_values.end(), v) -
                                   region_values.begin())
                : -1);
    }
  }

  material::MaterialFit fit;
  {
    Progress progress("fit", o.common.progress_mode());
    options.progress = [&progress](double fraction) { progress.Update(fraction); };
    try {
      fit = material::FitMaterial(data, normals, options);
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      const bool about_normals = what.find("normal") != std::string::npos;
      throw std::runtime_error((about_normals ? normals_source : o.dataset) + ": " + what);
    }
  }
  const material::ModelFit& best = fit.best();
  const bool per_group = options.albedo != material::AlbedoMode::kPerPixel;

  // material.json: what `iphong render` (a scene's "material": {"file": …}) and `iphong
  // normals` (a dataset's material.json) read. The ambient term is stored as ka with Ia = 1.
  nlohmann::json material_json = {
      {"model", reflectance::LobeName(best.lobe)},
      {"ambient", {1, 1, 1}},
      {"ka", Triple(best.ambient_term)},
      {"ks", Triple(best.ks)},
      {"shininess", best.lobe == reflectance::Lobe::kLambert ? 1.0 : best.shininess}};
  if (per_group && best.kd.size() == 1) material_json["kd"] = Triple(best.kd[0]);
  material_json["comment"] =
      "fitted by iphong fit-material; ka is the ambient term Ia*ka (Ia = 1)" +
      std::string(!per_group              ? "; kd varies per pixel: albedo.exr"
                  : region_values.empty() ? ""
                                          : "; kd varies per region: fit.json, albedo.exr");

  nlohmann::json report;
  report["iphong_version"] = kVersion;
  report["dataset"] = o.dataset;
  report["normals"] = normals_source;
  report["chosen"] = reflectance::LobeName(best.lobe);
  report["choice"] = fit.choice_note;
  report["folds"] = options.folds;
  report["fold_of_light"] = fit.fold;
  report["albedo"] = o.regions.empty() ? o.albedo : "per region";
  if (!region_values.empty()) {
    report["regions"] = o.regions;
    report["region_values"] = region_values;  // kd[i] belongs to the i-th value, in order
  }
  report["pixels"] = fit.pixels;
  report["fitted_pixels"] = fit.fitted_pixels;
  report["saturated_observations"] = fit.saturated;
  report["censored_observations"] = fit.censored;
  nlohmann::json models = nlohmann::json::array();
  for (const material::ModelFit& m : fit.models) models.push_back(ModelJson(m, per_group));
  report["models"] = models;
  nlohmann::json lobe = nlohmann::json::array();
  for (const material::LobeBin& b : fit.lobe) {
    lobe.push_back({{"angle_deg", b.angle_deg},
                    {"mean", b.mean},
                    {"standard_error", b.standard_error},
                    {"count", b.count}});
  }
  if (fit.lobe_model >= 0) {
    report["lobe"] = {{"model", reflectance::LobeName(fit.models[fit.lobe_model].lobe)},
                      {"bins", lobe}};
  }
  report["seconds"] = fit.summary.seconds;

  // Pictures: four lights spread over the capture, observed against predicted.
  ImageF albedo(data.width, data.height, 3);
  Mask fitted(data.width, data.height, false);
  for (std::size_t p = 0; p < data.pixel_count(); ++p) {
    if (!fit.albedo[p].allFinite()) continue;
    fitted.inside[data.pixels[p]] = 1;
    for (int c = 0; c < 3; ++c)
      albedo.pixels[3 * std::size_t(data.pixels[p]) + c] = fit.albedo[p][c];
  }
  std::vector<ImageF> observed, predicted;
  std::vector<std::string> labels;
  const int shown = std::min(4, data.images);
  for (int i = 0; i < shown; ++i) {
    const int j = static_cast<int>((i + 0.5) * data.images / shown);
    observed.push_back(material::ObservedImage(data, j));
    predicted.push_back(material::PredictImage(data, normals, best, fit.albedo, j));
    labels.push_back("light " + std::to_string(j + 1));
  }
  ImageF normals_out(data.width, data.height, 3);
  for (std::size_t p = 0; p < data.pixel_count(); ++p) {
    if (normals[p].squaredNorm() == 0) continue;
    const Vec3d n = normals[p].normalized();
    for (int c = 0; c < 3; ++c) normals_out.pixels[3 * std::size_t(data.pixels[p]) + c] = n[c];
  }

  io::WriteTextFile(out.file("material.json"), material_json.dump(2) + "\n");
  io::WriteTextFile(out.file("fit.json"), report.dump(2) + "\n");
  io::WriteImage(out.file("albedo.exr"), albedo);
  io::WriteAlbedoPicture(out.file("albedo.png"), albedo, fitted);
  io::WriteImage(out.file("normals.exr"), normals_out);
  io::WriteComparisonPicture(out.file("compare.png"), observed, predicted, labels);
  if (fit.lobe_model >= 0) {
    const material::ModelFit& m = fit.models[fit.lobe_model];
    const std::string title = reflectance::LobeName(m.lobe) + " lobe" +
                              (fit.lobe_model == fit.chosen ? "" : " (not chosen)") +
                              ": (observation - ambient - diffuse) / (E ks), luminance";
    io::WriteLobePlot(out.file("lobe.png"), fit.lobe, m.lobe, m.shininess, title);
  }
  out.Commit();
  PrintJson(o.common, report.dump(2));

  Say(o.common, "Fitted %zu of %zu pixels x %d lights in %.1f s (held-out choice %.1f s)\n",
      fit.fitted_pixels, fit.pixels, data.images, fit.summary.seconds, fit.summary.choice_seconds);
  Say(o.common, "  %-12s %14s %9s %14s  %s\n", "model", "held-out RMSE", "/ noise", "BIC",
      "ks, shininess");
  for (const material::ModelFit& m : fit.models) {
    std::string specular = "-";
    if (m.lobe != reflectance::Lobe::kLambert) {
      char text[96];
      std::snprintf(text, sizeof text, "[%.3g %.3g %.3g], %.3g", m.ks[0], m.ks[1], m.ks[2],
                    m.shininess);
      specular = text;
    }
    Say(o.common, "  %-12s %14.4g %9.2f %14.6g  %s\n", reflectance::LobeName(m.lobe).c_str(),
        m.heldout_rmse, m.heldout_ratio, m.bic, specular.c_str());
  }
  Say(o.common, "Chosen: %s (%s)\n", reflectance::LobeName(best.lobe).c_str(),
      fit.choice_note.c_str());
  for (int c = 0; c < 3; ++c) {
    const char* channel[] = {"red", "green", "blue"};
    Say(o.common, "  %-5s ka*Ia %s", channel[c],
        WithError(best.ambient_term[c], best.ambient_se[c], best.ambient_robust_se[c], "%.4g")
            .c_str());
    if (best.lobe != reflectance::Lobe::kLambert) {
      Say(o.common, ", ks %s (correlation with n %.2f)",
          WithError(best.ks[c], best.ks_se[c], best.ks_robust_se[c], "%.4g").c_str(),
          best.ks_shininess_correlation[c]);
    }
    if (per_group && best.kd.size() == 1) {
      Say(o.common, ", kd %s",
          WithError(best.kd[0][c], best.kd_se.empty() ? NAN : best.kd_se[0][c], NAN, "%.4g")
              .c_str());
    }
    Say(o.common, "\n");
  }
  if (best.lobe != reflectance::Lobe::kLambert) {
    Say(o.common, "  shininess %s\n",
        WithError(best.shininess, best.shininess_se, best.shininess_robust_se, "%.4g").c_str());
  }
  Say(o.common, "Noise estimate %.3g; %zu observations saturated, %zu censored as shadow\n",
      best.sigma, fit.saturated, fit.censored);
  Say(o.common,
      "Wrote %s: material.json, fit.json, albedo.exr/.png, normals.exr, compare.png%s (%.1f s)\n",
      o.output_dir.c_str(), fit.lobe_model >= 0 ? ", lobe.png" : "", SecondsSince(start));
}

}  // namespace

void AddFitMaterialCommand(CLI::App& app) {
  auto o = std::make_shared<FitMaterialCommandOptions>();
  auto* cmd = app.add_subcommand(
      "fit-material",
      "Fit the material (ka*Ia, kd, ks, shininess) with standard errors to a capture of known "
      "normals; choose Lambert, Phong or Blinn-Phong by held-out lights");
  cmd->add_option("dataset", o->dataset, "Capture folder (any layout iphong reads)")->required();
  cmd->add_option("--normals", o->normals,
                  "The object's normals: a normal map (EXR, PNG, Normal_gt.mat), an `iphong "
                  "normals` output folder, or a dataset folder with ground truth (the capture "
                  "itself)");
  cmd->add_flag("--sphere", o->sphere,
                "The object is a sphere: its normals from the circle fitted to the mask");
  cmd->add_option("-o,--output", o->output_dir,
                  "Output folder: new or empty, or an earlier fit-material output with "
                  "--overwrite")
      ->required();
  cmd->add_option("--model", o->models,
                  "Models to fit and choose from (default: lambert phong blinn-phong); one model "
                  "skips the choice")
      ->check(CLI::IsMember({"phong", "blinn-phong", "lambert"}))
      ->delimiter(',');
  cmd->add_option("--albedo", o->albedo, "kd per pixel, or one for the whole object")
      ->check(CLI::IsMember({"per-pixel", "uniform"}))
      ->capture_default_str();
  cmd->add_option("--regions", o->regions,
                  "A label image: one kd per distinct value of its first channel (0: left out), "
                  "ks and the shininess shared (instead of --albedo)");
  cmd->add_option("--folds", o->folds,
                  "Interleaved folds of the lights for the held-out choice (light j in fold j "
                  "mod F; 2 = odd against even)")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  cmd->add_option("--max-pixels", o->max_pixels,
                  "Pixels the coefficients are fitted to (an even sample; kd is solved for all)")
      ->check(CLI::Range(1, 100000000))
      ->capture_default_str();
  cmd->add_option("--saturation", o->saturation,
                  "Observations with a channel at or above this are unused (at most 1: not in "
                  "pixels whose float values pass 1)")
      ->check(Positive())
      ->capture_default_str();
  cmd->add_option("--shadow-threshold", o->shadow_threshold,
                  "Observations darker than the model by more than this fraction of the pixel's "
                  "brightness count as shadowed (censored)")
      ->check(CLI::Range(0.001, 0.999))
      ->capture_default_str();
  AddCaptureOptions(cmd, o->capture);
  AddOverwriteOption(cmd, o->common);
  AddThreadsOption(cmd, o->common);
  AddMemoryOption(cmd, o->common);
  AddReportOptions(cmd, o->common);
  cmd->callback([o] { RunFitMaterial(*o); });
}

}  // namespace iphong::cli
