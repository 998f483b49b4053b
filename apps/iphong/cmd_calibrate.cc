// `iphong calibrate-lights IMAGES -o DIR`: light directions (and intensities, and point-light
// positions) from photos of a mirror sphere, a matte sphere or an object with known normals.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "calibrate/lights.h"
#include "core/timing.h"
#include "core/version.h"
#include "io/calibration_picture.h"
#include "io/dataset.h"
#include "io/dataset_text.h"
#include "io/files.h"
#include "io/image_io.h"
#include "io/output_folder.h"
#include "io/visualize.h"
#include "iphong/commands.h"
#include "iphong/console.h"

namespace iphong::cli {
namespace {

struct CalibrateOptions {
  std::string images;
  std::string output_dir;
  std::string sphere = "mirror";
  std::string normals;             // a normal map: calibrate from known normals
  std::vector<double> circles;     // cx, cy, r [, cx, cy, r]
  std::vector<double> intrinsics;  // fx, fy, cx, cy
  int max_spheres = 2;
  double sphere_radius_mm = 0;  // > 0: light positions in mm
  double saturation = 1.0;
  bool uniform_albedo = false;
  CaptureFlags capture;
  CommonOptions common;
};

nlohmann::json Vector(const Vec3d& v) { return {v.x(), v.y(), v.z()}; }

// The brightest value of every pixel over the images: each highlight shows in one picture.
ImageF Brightest(const std::vector<ImageF>& images) {
  ImageF out = images[0];
  for (const ImageF& image : images)
    for (std::size_t i = 0; i < out.pixels.size(); ++i)
      out.pixels[i] = std::max(out.pixels[i], image.pixels[i]);
  return out;
}

// The near-light layout of triangulated positions (io/near_capture.h), and how near the lights
// are: in the spheres' diameters from their midpoint, and what that does across an object of the
// spheres' size — its directions turn by up to 2·asin(r/d), its irradiance changes by
// (1 ± r/d)⁻² — against what distant lights assume.
struct NearLayout {
  std::vector<Vec3d> positions;
  io::CameraIntrinsics camera;
  nlohmann::json report;
  std::string summary;
};

NearLayout NearLayoutOf(const std::vector<Vec3d>& positions_cal, const nlohmann::json& report,
                        const calibrate::Intrinsics& intrinsics, double sphere_radius_mm, int width,
                        int height) {
  NearLayout n;
  const nlohmann::json& spheres = report["spheres"];
  Vec3d centre = Vec3d::Zero();
  double radius = 0, radius_px = 0;
  for (const nlohmann::json& s : spheres) {
    centre += Vec3d(s["center_cam"][0], s["center_cam"][1], s["center_cam"][2]);
    radius += s["radius"].get<double>();
    radius_px += s["radius_px"].get<double>();
  }
  centre /= static_cast<double>(spheres.size());
  radius /= static_cast<double>(spheres.size());
  radius_px /= static_cast<double>(spheres.size());
  // Calibration units: pixels (orthographic) or sphere radii (perspective); mm with the radius.
  const double mm = sphere_radius_mm > 0 ? sphere_radius_mm / radius : 1.0;
  std::vector<double> sizes, turn, change;
  for (const Vec3d& s : positions_cal) {
    const double d = (s - centre).norm();
    sizes.push_back(d / (2 * radius));
    turn.push_back(2 * std::asin(std::min(1.0, radius / d)) * 180 / M_PI);
    change.push_back(100 * (1 / std::pow(1 - std::min(0.99, radius / d), 2) - 1));
  }
  n.camera.perspective = intrinsics.perspective();
  if (n.camera.perspective) {
    n.camera.fx = intrinsics.fx, n.camera.fy = intrinsics.fy;
    n.camera.cx = intrinsics.cx, n.camera.cy = intrinsics.cy;
    for (const Vec3d& s : positions_cal) n.positions.push_back(s * mm);
  } else {
    // The orthographic frame of the layout is centred on the image, its origin in front of
    // every light (the object, the spheres' plane, at the depth of the nearest light's z plus a
    // radius).
    double front = 0;
    for (const Vec3d& s : positions_cal) front = std::max(front, s.z());
    front += radius;
    n.camera.pixel_size = mm;
    for (const Vec3d& s : positions_cal) {
      n.positions.push_back(Vec3d(s.x() - width / 2.0, s.y() + height / 2.0, s.z() - front) * mm);
    }
  }
  const auto [lo, hi] = std::minmax_element(sizes.begin(), sizes.end());
  const double worst_turn = *std::max_element(turn.begin(), turn.end());
  const double worst_change = *std::max_element(change.begin(), change.end());
  std::vector<double> sorted = sizes;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  // A degree is what the best captures' normals are good to: lights whose directions turn less
  // than that across the object can be taken as distant.
  const bool distant = worst_turn < 1;
  char text[400];
  std::snprintf(text, sizeof text,
                "Lights %.3g to %.3g sphere diameters from the spheres (median %.3g): across an "
                "object of the spheres' size their directions turn by up to %.2g deg and their "
                "irradiance changes by up to %.2g%%: %s",
                *lo, *hi, sorted[sorted.size() / 2], worst_turn, worst_change,
                distant ? "distant lights would do (light_directions.txt)"
                        : "use the near-light layout (light_positions.txt, camera.json)");
  n.summary = text;
  n.report = {{"units", sphere_radius_mm > 0   ? "mm"
                        : n.camera.perspective ? "sphere radii (give --sphere-radius for mm)"
                                               : "pixels (give --sphere-radius for mm)"},
              {"distance_in_sphere_diameters",
               {{"min", *lo}, {"max", *hi}, {"median", sorted[sorted.size() / 2]}}},
              {"largest_direction_turn_deg", worst_turn},
              {"largest_irradiance_change_percent", worst_change},
              {"distant_would_do", distant},
              {"sphere_radius_px", radius_px}};
  return n;
}

void RunCalibrate(const CalibrateOptions& o) {
  const auto start = Clock::now();
  RequireFolder(o.images);
  if (o.circles.size() % 3 != 0) {
    throw CLI::ValidationError("--circle", "takes cx,cy,r (one sphere) or six numbers (two)");
  }
  calibrate::Intrinsics camera;
  if (!o.intrinsics.empty()) {
    camera = {o.intrinsics[0], o.intrinsics[1], o.intrinsics[2], o.intrinsics[3]};
    if (std::string m = camera.Check(); !m.empty() || !camera.perspective()) {
      throw CLI::ValidationError("--intrinsics",
                                 "fx and fy must be between 1e-12 and 1e12, cx and cy finite");
    }
  }
  const bool known_normals = !o.normals.empty();
  if (known_normals && o.sphere != "mirror") {
    throw CLI::ValidationError("--normals", "calibrates from the normal map; drop --sphere");
  }
  io::OutputFolderOptions folder;
  folder.command = "calibrate-lights";
  folder.overwrite = o.common.overwrite;
  folder.inputs = {o.images, o.capture.options.mask, o.normals};
  io::OutputFolder out(o.output_dir, folder);

  io::DatasetLoadOptions load;
  load.capture = o.capture.resolved();
  load.capture.lights_needed = false;
  load.load_ground_truth = false;
  load.threads = o.common.threads;
  load.memory = o.common.memory();
  io::Dataset dataset;
  {
    Progress decode("decode", o.common.progress_mode());
    load.progress = [&decode](double fraction) { decode.Update(fraction); };
    dataset = io::LoadDataset(o.images, load);
  }
  Say(o.common, "Read %s: %s\n", o.images.c_str(), io::DescribeDataset(dataset).c_str());
  for (const std::string& warning : dataset.warnings) Warn(warning);
  std::vector<const ImageF*> images;
  for (const ImageF& image : dataset.images) images.push_back(&image);
  const std::size_t k = images.size();
  auto name = [&](int j) { return dataset.files.paths[j]; };

  nlohmann::json report;
  report["iphong_version"] = kVersion;
  report["images"] = o.images;
  report["method"] = known_normals ? "known normals" : o.sphere + " sphere";
  report["camera"] = camera.perspective() ? nlohmann::json{{"fx", camera.fx},
                                                           {"fy", camera.fy},
                                                           {"cx", camera.cx},
                                                           {"cy", camera.cy}}
                                          : nlohmann::json("orthographic");
  std::vector<Vec3d> directions, intensities, positions;
  std::vector<calibrate::CalibrationNote> notes;
  io::CalibrationPictureInput picture;
  const ImageF brightest = Brightest(dataset.images);
  picture.background = &brightest;
  picture.labels = io::ImageLabels(dataset.filenames);
  nlohmann::json per_image = nlohmann::json::array();
  std::string intensity_source;

  // A matte sphere or a normal map: the shading's inverse (known_normals.cc).
  auto from_normals = [&](const ImageF& normals, const Mask& where, bool uniform_albedo) {
    calibrate::KnownNormalOptions options;
    options.saturation = o.saturation;
    options.uniform_albedo = uniform_albedo;
    options.threads = o.common.threads;
    const calibrate::KnownNormalCalibration c =
        calibrate::CalibrateFromNormals(images, normals, where, options);
    if (!c.failed.empty()) {
      throw std::runtime_error(
          dataset.files.paths[c.failed[0]] + ": no pixel is lit in this photo where the normals " +
          (known_normals ? "of " + o.normals : std::string("of the sphere")) + " say (" +
          std::to_string(c.failed.size()) +
          " photos so): the light misses the object, or the normals are not the object's");
    }
    directions = c.light_dir_cam;
    intensities = c.light_intensities;
    notes = c.warnings;
    intensity_source = "measured (relative; each channel's mean is 1)";
    report["rounds"] = c.rounds;
    report["converged"] = c.converged;
    report["last_move_deg"] = c.last_move_deg;
    report["seconds"] = c.seconds;
    for (std::size_t j = 0; j < k; ++j) {
      per_image.push_back({{"file", dataset.filenames[j]},
                           {"light_direction", Vector(directions[j])},
                           {"intensity", Vector(intensities[j])},
                           {"relative_residual", c.residual[j]},
                           {"pixels_used", c.pixels_used[j]}});
    }
  };

  if (known_normals) {
    Mask normal_mask;
    ImageF normals = io::ReadNormalMap(o.normals, false, &normal_mask, o.common.memory());
    if (normals.width != dataset.width() || normals.height != dataset.height()) {
      throw std::runtime_error(o.normals + ": is " + SizeText(normals.width, normals.height) +
                               ", the images are " + SizeText(dataset.width(), dataset.height()));
    }
    for (const std::string& w : io::CheckNormalMap(normals, &dataset.mask, o.normals)) Warn(w);
    from_normals(normals, dataset.mask, o.uniform_albedo);
  } else {
    std::vector<calibrate::SphereOutline> outlines;
    std::vector<std::string> sphere_warnings;
    if (!o.circles.empty()) {
      for (std::size_t i = 0; i < o.circles.size(); i += 3) {
        calibrate::SphereOutline s;
        s.center_x_px = o.circles[i];
        s.center_y_px = o.circles[i + 1];
        s.radius_px = o.circles[i + 2];
        if (!(s.radius_px > 0)) throw CLI::ValidationError("--circle", "the radius must be > 0");
        if (std::string m = calibrate::CheckCircle(s, dataset.width(), dataset.height());
            !m.empty()) {
          throw CLI::ValidationError("--circle", m);
        }
        outlines.push_back(s);
      }
    } else {
      calibrate::SphereSearch search;
      search.max_spheres = o.max_spheres;
      const bool masked = !dataset.files.mask_path.empty();
      const std::string source = masked ? dataset.files.mask_path : o.images;
      try {
        outlines = masked ? calibrate::FindSpheres(dataset.mask, search, &sphere_warnings)
                          : calibrate::FindSpheresInImages(images, search, &sphere_warnings);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(source + ": " + e.what());
      }
    }
    for (const std::string& w : sphere_warnings)
      Warn((dataset.files.mask_path.empty() ? o.images : dataset.files.mask_path) + ": " + w);
    std::vector<calibrate::SphereGeometry> spheres;
    for (const calibrate::SphereOutline& s : outlines) {
      spheres.push_back(calibrate::SphereFromOutline(s, camera));
      picture.circles.emplace_back(s.center_x_px, s.center_y_px, s.radius_px);
    }
    nlohmann::json sphere_json = nlohmann::json::array();
    for (const calibrate::SphereGeometry& s : spheres) {
      sphere_json.push_back({{"center_px", {s.outline.center_x_px, s.outline.center_y_px}},
                             {"radius_px", s.outline.radius_px},
                             {"outline_rms_px", s.outline.fit_rms_px},
                             {"visible_fraction", s.outline.visible_fraction},
                             {"center_cam", Vector(s.center_cam)},
                             {"radius", s.radius}});
    }
    report["spheres"] = sphere_json;
    if (o.sphere == "mirror") {
      calibrate::MirrorOptions options;
      options.saturation = o.saturation;
      options.threads = o.common.threads;
      const calibrate::MirrorCalibration c = calibrate::CalibrateMirror(images, spheres, options);
      if (!c.failed.empty()) {
        std::string list;
        for (std::size_t i = 0; i < c.failed.size() && i < 3; ++i) {
          for (const calibrate::Highlight& h : c.highlights[c.failed[i]])
            if (!h.found) list += (list.empty() ? "" : "; ") + name(c.failed[i]) + ": " + h.problem;
        }
        if (c.failed.size() > 3) list += " (and " + std::to_string(c.failed.size() - 3) + " more)";
        throw std::runtime_error(list);
      }
      directions = c.light_dir_cam;
      intensities = c.light_intensities;
      positions = c.light_position_cam;
      notes = c.warnings;
      intensity_source =
          c.intensities_measured ? "measured from the highlights' energy" : "not measured (all 1)";
      if (!c.positions_note.empty() && spheres.size() == 2) Warn(c.positions_note);
      report["seconds"] = c.seconds;
      for (std::size_t j = 0; j < k; ++j) {
        nlohmann::json found = nlohmann::json::array();
        picture.marks.emplace_back();
        for (const calibrate::Highlight& h : c.highlights[j]) {
          found.push_back({{"center_px", {h.x_px, h.y_px}},
                           {"uncertainty_px", h.uncertainty_px},
                           {"uncertainty_deg", h.uncertainty_deg},
                           {"spread_deg", h.spread_deg},
                           {"pixels", h.pixels},
                           {"saturated_pixels", h.saturated_pixels},
                           {"highlights", h.blobs},
                           {"light_direction", Vector(h.light_dir_cam)}});
          picture.marks.back().emplace_back(h.x_px, h.y_px);
        }
        nlohmann::json entry = {{"file", dataset.filenames[j]},
                                {"light_direction", Vector(directions[j])},
                                {"intensity", Vector(intensities[j])},
                                {"highlights", found}};
        if (!positions.empty()) {
          entry["light_position"] = Vector(positions[j]);
          entry["triangulation_gap"] = c.triangulation_gap[j];
        }
        per_image.push_back(entry);
      }
    } else {  // matte sphere: known normals from the fitted sphere, one albedo
      Mask on_sphere;
      const ImageF normals =
          calibrate::SphereNormalMap(spheres, dataset.width(), dataset.height(), &on_sphere);
      from_normals(normals, on_sphere, true);
    }
  }

  nlohmann::json warnings = nlohmann::json::array();
  for (const calibrate::CalibrationNote& n : notes) {
    std::string line = n.image < 0 ? o.images : name(n.image);
    if (n.other >= 0) line += " and " + dataset.filenames[n.other];
    line += ": " + n.text;
    Warn(line);
    warnings.push_back(line);
  }
  report["warnings"] = warnings;
  report["intensities"] = intensity_source;
  report["per_image"] = per_image;
  picture.light_dir_cam = directions;

  io::WriteTextFile(out.file("light_directions.txt"), io::FormatTriples(directions));
  io::WriteTextFile(out.file("light_intensities.txt"), io::FormatTriples(intensities));
  std::string nearness;
  if (!positions.empty()) {
    const NearLayout layout = NearLayoutOf(positions, report, camera, o.sphere_radius_mm,
                                           dataset.width(), dataset.height());
    io::WriteTextFile(out.file("light_positions.txt"), io::FormatTriples(layout.positions));
    io::WriteTextFile(out.file("camera.json"), io::FormatCameraJson(layout.camera));
    report["near_lights"] = layout.report;
    nearness = layout.summary;
  }
  io::WriteTextFile(out.file("lights.lp"), io::FormatLp(dataset.filenames, directions));
  io::WriteImage(out.file("calibration.png"), io::CalibrationPicture(picture));
  report["total_seconds"] = SecondsSince(start);
  io::WriteTextFile(out.file("calibration.json"), report.dump(2) + "\n");
  out.Commit();
  PrintJson(o.common, report.dump(2));
  Say(o.common, "Calibrated %zu lights (%s; intensities %s) in %.2f s\n", k,
      report["method"].get<std::string>().c_str(), intensity_source.c_str(), SecondsSince(start));
  if (!nearness.empty()) Say(o.common, "%s\n", nearness.c_str());
  Say(o.common,
      "Wrote %s: light_directions.txt, light_intensities.txt, lights.lp%s, calibration.json, "
      "calibration.png\n",
      o.output_dir.c_str(),
      positions.empty() ? "" : ", light_positions.txt and camera.json (the near-light layout)");
}

}  // namespace

void AddCalibrateCommand(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  auto* cmd = app.add_subcommand(
      "calibrate-lights",
      "Light directions and intensities from photos of a mirror or matte sphere, or of an object "
      "with known normals");
  cmd->add_option("images", o->images,
                  "Folder of the calibration photos, one per light (a list file, or natural order)")
      ->required();
  cmd->add_option("-o,--output", o->output_dir,
                  "Output folder: new or empty, or an earlier calibrate-lights output with "
                  "--overwrite")
      ->required();
  cmd->add_option("--sphere", o->sphere,
                  "What the photos show: a mirror sphere (the highlights give the directions) or "
                  "a matte one (the shading gives directions and intensities)")
      ->check(CLI::IsMember({"mirror", "matte"}))
      ->capture_default_str();
  cmd->add_option("--normals", o->normals,
                  "Known normals of what the photos show (Normal_gt.mat, EXR, PNG): calibrate "
                  "from its shading (directions and intensities) instead of a sphere");
  cmd->add_flag("--uniform-albedo", o->uniform_albedo,
                "With --normals: the object has one albedo (a painted target), not one per pixel");
  cmd->add_option("--circle", o->circles,
                  "The sphere's circle in pixels, cx,cy,r (six numbers for two spheres) instead "
                  "of fitting one to the mask")
      ->delimiter(',');
  cmd->add_option("--intrinsics", o->intrinsics,
                  "Perspective camera fx,fy,cx,cy in pixels (default: orthographic)")
      ->delimiter(',')
      ->expected(4);
  cmd->add_option("--sphere-radius", o->sphere_radius_mm,
                  "The spheres' radius in mm: light_positions.txt in mm (else in sphere radii, "
                  "or pixels for an orthographic camera)")
      ->check(Scale());
  cmd->add_option("--spheres", o->max_spheres, "Most spheres to look for in the mask")
      ->check(CLI::Range(1, 2))
      ->capture_default_str();
  cmd->add_option("--saturation", o->saturation,
                  "Values at or above this are clipped (images read as 0-1; at most 1: not where a "
                  "float image passes 1)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            double v = 0;
            if (!CLI::detail::lexical_cast(text, v) || !(v > 0 && v <= 1))
              return "must be a number in (0, 1] (got " + text + ")";
            return "";
          },
          "(0, 1]"))
      ->capture_default_str();
  cmd->add_option("--mask", o->capture.options.mask,
                  "Mask picture of the sphere(s) or object (default: mask.png, mask.*, "
                  "NAME.mask.*, NAME_mask.*)");
  cmd->add_option("--encoding", o->capture.options.encoding,
                  "How the image values are encoded: auto, linear, srgb")
      ->check(CLI::IsMember({"auto", "linear", "srgb"}))
      ->capture_default_str();
  AddOverwriteOption(cmd, o->common);
  AddThreadsOption(cmd, o->common);
  AddMemoryOption(cmd, o->common);
  AddReportOptions(cmd, o->common);
  cmd->callback([o] { RunCalibrate(*o); });
}

}  // namespace iphong::cli
