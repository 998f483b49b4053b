// `iphong normals` on a near-light capture (io/near_capture.h): the capture's point lights, the
// loop of near/near.h, and what it adds to the outputs — depth.exr and the mesh in mm, and
// metrics.json's "near_lights".
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/timing.h"
#include "geometry/height_map.h"
#include "io/files.h"
#include "io/image_io.h"
#include "io/near_capture.h"
#include "io/surface.h"
#include "iphong/console.h"
#include "iphong/normals_command.h"
#include "near/near.h"
#include "reflectance/lighting.h"
#include "solve/model_choice.h"
#include "solve/normals.h"

namespace iphong::cli {
namespace {

// The camera of the files, as the working images (--crop, --downscale) see it.
geometry::HeightMapFrame WorkingFrame(const NormalsCommandOptions& o, const io::Dataset& d) {
  geometry::HeightMapFrame frame = d.files.near.frame();
  const io::CaptureOptions capture = o.capture.resolved();
  if (capture.crop.width > 0) {
    if (!frame.perspective) {
      throw std::runtime_error(d.files.near.camera_path +
                               ": an orthographic camera is centred on the whole image; --crop "
                               "of an orthographic near-light capture is not supported");
    }
    frame.cx -= capture.crop.x;
    frame.cy -= capture.crop.y;
  }
  const double s = capture.downscale;
  frame.fx /= s;
  frame.fy /= s;
  frame.cx /= s;
  frame.cy /= s;
  if (!frame.perspective) frame.pixel_size *= s;
  return frame;
}

// A light at the surface (where 1/d² has no meaning: within 5 % of the object's radius) or
// inside the object (behind its visible
// surface, as the camera sees it): one line naming light_positions.txt's line.
void CheckLightsOutsideSurface(const io::NearLightFiles& files, const near::NearResult& r,
                               const geometry::HeightMapFrame& frame, const Mask& mask) {
  std::vector<Vec3d> points;
  Vec3d mean = Vec3d::Zero();
  for (std::size_t p = 0; p < mask.inside.size(); ++p) {
    if (!mask.inside[p] || !(r.depth.pixels[p] > 0)) continue;
    const float* x = r.points.pixels.data() + 3 * p;
    points.emplace_back(x[0], x[1], x[2]);
    mean += points.back();
  }
  if (points.empty()) return;
  mean /= static_cast<double>(points.size());
  double extent = 0;
  for (const Vec3d& x : points) extent = std::max(extent, (x - mean).norm());
  for (std::size_t j = 0; j < files.positions_mm.size(); ++j) {
    const Vec3d& s = files.positions_mm[j];
    double nearest = INFINITY;
    for (const Vec3d& x : points) nearest = std::min(nearest, (x - s).norm());
    char text[320];
    // Within a twentieth of the object's radius of its surface, a millimetre's error in the
    // surface changes that light's 1/d² by tens of percent: no fit can stand on it.
    if (nearest < 0.05 * extent) {
      std::snprintf(text, sizeof text,
                    "light %zu is at the object's surface (%.3g mm from it, the object %.3g mm "
                    "across): the inverse-square law has no meaning there",
                    j + 1, nearest, 2 * extent);
      throw std::runtime_error(files.positions_path + ":" +
                               std::to_string(files.position_lines[j]) + ": " + text);
    }
    // Where the camera sees the light: behind the surface there, it is inside or behind the
    // object and cannot light what the camera sees.
    double u = 0, v = 0;
    if (frame.perspective) {
      if (!(s.z() < 0)) continue;
      u = frame.cx + frame.fx * s.x() / -s.z();
      v = frame.cy - frame.fy * s.y() / -s.z();
    } else {
      u = s.x() / frame.pixel_size + mask.width / 2.0;
      v = mask.height / 2.0 - s.y() / frame.pixel_size;
    }
    const int col = static_cast<int>(std::floor(u)), row = static_cast<int>(std::floor(v));
    if (col < 0 || row < 0 || col >= mask.width || row >= mask.height || !mask.at(col, row)) {
      continue;
    }
    const double surface = r.depth.pixels[static_cast<std::size_t>(row) * mask.width + col];
    if (surface > 0 && -s.z() > surface + 0.01 * extent) {
      std::snprintf(text, sizeof text,
                    "light %zu is inside or behind the object (%.4g mm deep where the surface "
                    "at pixel (%d, %d) is %.4g mm): it cannot light what the camera sees",
                    j + 1, -s.z(), col, row, surface);
      throw std::runtime_error(files.positions_path + ":" +
                               std::to_string(files.position_lines[j]) + ": " + text);
    }
  }
}

// An LED that sends no light to any point of the surface (the model's LED factor 0 at each: its
// axis faces away) must have a dark photo. Lit, the axis is the wrong way round (light_axes.txt
// gives the way each LED points, toward what it lights) or another light's: the fit would explain
// a lit photo by a light that sends nothing. "Lit": its mean inside the mask at least a quarter of
// the median photo's, as no shadow darkens a whole photo that much less than its own light's
// fall-off allows.
void CheckLedAxesFaceTheObject(const io::NearLightFiles& files, const near::NearResult& r,
                               const solve::PhotometricData& observations) {
  if (files.axes.empty() || files.anisotropy.empty()) return;
  const int k = observations.images;
  std::vector<double> mean(k, 0.0);
  for (std::size_t i = 0; i < observations.pixels.size(); ++i) {
    for (int j = 0; j < k; ++j) {
      const float* v = observations.values.data() + (i * k + j) * 3;
      mean[j] += double(v[0]) + v[1] + v[2];
    }
  }
  std::vector<double> sorted = mean;
  std::nth_element(sorted.begin(), sorted.begin() + k / 2, sorted.end());
  const double median = sorted[k / 2];
  if (!(median > 0)) return;
  const std::vector<reflectance::Light> lights =
      io::NearPointLights(files, std::vector<Vec3d>(files.positions_mm.size(), Vec3d::Ones()));
  for (int j = 0; j < k; ++j) {
    if (!(files.anisotropy[j] > 0) || mean[j] < 0.25 * median) continue;
    bool lights_some = false, surface = false;
    for (std::size_t p = 0; p < r.depth.pixels.size() && !lights_some; ++p) {
      if (!(r.depth.pixels[p] > 0)) continue;
      surface = true;
      const float* x = r.points.pixels.data() + 3 * p;
      Vec3d direction, diffuse, specular;
      lights_some = reflectance::LightAt(lights[j], Vec3d(x[0], x[1], x[2]), &direction, &diffuse,
                                         &specular) &&
                    diffuse.maxCoeff() > 0;
    }
    if (!surface || lights_some) continue;
    throw std::runtime_error(
        files.axes_path + ":" + std::to_string(files.axis_lines[j]) + ": LED " +
        std::to_string(j + 1) +
        "'s axis faces away from every point of the object's surface, so it would light "
        "nothing, yet its photo is lit: an axis gives the way the LED points, toward the object "
        "(negated?)");
  }
}

}  // namespace

solve::PhotometricData NearRunData(const io::Dataset& d, const solve::PhotometricData& observations,
                                   const NearRun& run, std::size_t sample) {
  // Only the check's spread sample: a copy of every observation would double the run's memory.
  solve::PhotometricData data = solve::SubsetObservations(
      observations,
      solve::SpreadIndices(observations.pixel_count(),
                           static_cast<int>(std::min(sample, observations.pixel_count()))));
  data.point_lights = io::NearPointLights(d.files.near, observations.light_intensities);
  data.perspective = run.frame.perspective;
  data.points_cam.resize(data.pixels.size());
  const ImageF& points = run.result.points;
  for (std::size_t i = 0; i < data.pixels.size(); ++i) {
    const std::size_t p = static_cast<std::size_t>(data.pixels[i]);
    data.points_cam[i] =
        Vec3d(points.pixels[3 * p], points.pixels[3 * p + 1], points.pixels[3 * p + 2]);
  }
  solve::SetReferenceLights(data, solve::MeanPoint(data));
  return data;
}

NearRun SolveNearCapture(const NormalsCommandOptions& o, const io::Dataset& d,
                         const solve::PhotometricData& observations,
                         const solve::NormalOptions& options) {
  NearRun run;
  run.frame = WorkingFrame(o, d);
  if (observations.images < 3) {
    throw std::runtime_error(d.files.near.positions_path +
                             ": near-light photometric stereo needs at least 3 images");
  }
  solve::PhotometricData data = observations;
  data.point_lights = io::NearPointLights(d.files.near, observations.light_intensities);
  near::NearOptions near_options;
  near_options.normals = options;
  near_options.distance = o.distance;
  near_options.log = [&o](const std::string& line) {
    Say(o.common, "  near lights: %s\n", line.c_str());
  };
  try {
    run.result = near::SolveNearLights(std::move(data), run.frame, near_options);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(o.dataset + ": " + e.what());
  }
  CheckLightsOutsideSurface(d.files.near, run.result, run.frame, d.mask);
  CheckLedAxesFaceTheObject(d.files.near, run.result, observations);
  // A lens's optical centre lies inside its barrel: nothing a camera images is nearer to it than
  // about a centimetre. Nearer, the positions are in other units than millimetres (metres read
  // as millimetres put the rig 1000 times nearer). The normals do not see that scale, as far as
  // nothing known (material.json's coefficients, the intensities) fixes it; the depth and the
  // mesh do.
  if (run.frame.perspective && run.result.distance < 10) {
    char text[320];
    std::snprintf(text, sizeof text,
                  ": the object comes out %.3g mm from the camera, nearer than any lens images: "
                  "are the positions in millimetres (metres read as millimetres put it 1000 "
                  "times nearer)? The depth and mesh are in those units",
                  run.result.distance);
    Warn(d.files.near.positions_path + text);
  }
  if (run.result.distance_from_images) {
    std::string others;
    for (double other : run.result.other_distances) {
      others += (others.empty() ? " (or, as well, at " : " or ") +
                std::to_string(static_cast<int>(std::lround(other))) + " mm";
    }
    if (!others.empty()) others += ": the images do not decide)";
    Warn(d.files.near.positions_path +
         ": the lights' layout does not say how far the object is (no LED axes meeting at it, "
         "no dome round it); the images put it at " +
         std::to_string(static_cast<int>(std::lround(run.result.distance))) + " mm" + others +
         ": give --distance MM if you know better");
  }
  return run;
}

near::EffectiveDistanceOptions EffectiveDistanceOptionsFor(const NormalsCommandOptions& o,
                                                           const solve::NormalOptions& options) {
  near::EffectiveDistanceOptions e;
  e.normals = options;
  if (o.light_distance == "inf") {
    e.distance_px = INFINITY;
  } else if (o.light_distance != "auto") {
    char* end = nullptr;
    e.distance_px = std::strtod(o.light_distance.c_str(), &end);
    if (end == o.light_distance.c_str() || *end != '\0' || !geometry::ScaleInRange(e.distance_px)) {
      throw std::invalid_argument(
          "--light-distance: expected auto, inf or a distance in pixels between 1e-12 and 1e12, "
          "got '" +
          o.light_distance + "'");
    }
  }
  e.log = [&o](const std::string& line) { Say(o.common, "  %s\n", line.c_str()); };
  return e;
}

nlohmann::json EffectiveDistanceJson(const near::EffectiveDistanceResult& r) {
  nlohmann::json candidates = nlohmann::json::array();
  for (const near::DistanceCandidate& c : r.scored) {
    candidates.push_back(
        {{"distance_px",
          std::isinf(c.distance_px) ? nlohmann::json("inf") : nlohmann::json(c.distance_px)},
         {"centre_behind_px", c.centre_behind_px},
         {"test", c.criterion},
         {"heldout_cost", c.heldout_cost},
         {"heldout_error", c.heldout_error}});
  }
  // Each proposed D checked against points placed by their normals (near::PositionCheck).
  nlohmann::json position_checks = nlohmann::json::array();
  for (const near::PositionCheck& c : r.position_checks) {
    position_checks.push_back({{"distance_px", c.distance_px},
                               {"test", c.criterion},
                               {"heldout_gain", c.gain},
                               {"heldout_gain_error", c.gain_error},
                               {"refused", c.refused}});
  }
  nlohmann::json passes = nlohmann::json::array();
  for (const near::NearPass& p : r.passes) {
    passes.push_back({{"light_distance_px", p.distance},
                      {"normals_moved_deg", p.change_deg},
                      {"lights_moved_deg", p.lights_moved_deg},
                      {"seconds", p.seconds}});
  }
  return {{"distance_px",
           std::isinf(r.distance_px) ? nlohmann::json("inf") : nlohmann::json(r.distance_px)},
          {"chosen", r.chosen},
          {"object_size_px", r.object_size_px},
          // The lights' centre behind the distant surface's centroid, and that surface's rim.
          {"centre_behind_px", r.centre_behind_px},
          {"relief_px", r.relief_px},
          {"test", r.criterion},
          {"heldout_gain", r.gain},
          {"heldout_gain_error", r.gain_error},
          // Where the diffuse test proposed a D: the object's model's loss there (refused beyond
          // its standard error); null when not asked.
          {"model_loss_at_diffuse_distance",
           std::isnan(r.model_loss) ? nlohmann::json() : nlohmann::json(r.model_loss)},
          {"model_loss_error",
           std::isnan(r.model_loss_error) ? nlohmann::json() : nlohmann::json(r.model_loss_error)},
          {"position_checks", position_checks},
          {"candidates", candidates},
          {"passes", passes},
          {"foil_refit", r.foil_refit},
          {"distant_seconds", r.distant_seconds},
          {"choice_seconds", r.choice_seconds},
          {"seconds", r.seconds}};
}

near::EffectiveDistanceResult SolveWithEffectiveDistance(
    const NormalsCommandOptions& o, const solve::PhotometricData& data,
    const solve::NormalOptions& options, nlohmann::json& metrics,
    std::optional<near::EffectiveDistanceResult> done, const std::vector<std::string>& done_log) {
  const near::EffectiveDistanceOptions e = EffectiveDistanceOptionsFor(o, options);
  near::EffectiveDistanceResult r;
  if (done) {
    r = std::move(*done);
    for (const std::string& line : done_log) e.log(line);
  } else {
    try {
      r = near::SolveEffectiveDistance(data, e);
    } catch (const std::invalid_argument& err) {
      throw std::runtime_error(o.dataset + ": " + err.what());
    }
  }
  if (o.light_distance == "inf") return r;
  metrics["effective_distance"] = EffectiveDistanceJson(r);
  return r;
}

void WriteNearOutputs(io::OutputFolder& out, const NearRun& run, const io::Dataset& d,
                      nlohmann::json& metrics, const CommonOptions& common) {
  const near::NearResult& r = run.result;
  io::WriteImage(out.file("depth.exr"), r.depth);
  // The surface the loop ended on, as a mesh in mm (io::WriteSurfaceFiles: height.exr is the
  // depth there, NaN outside).
  integrate::IntegrateResult surface;
  surface.height = ImageF(r.depth.width, r.depth.height, 1, NAN);
  surface.continuity = ImageF(r.depth.width, r.depth.height, 2, 1.0f);
  Mask placed = d.mask;
  for (std::size_t p = 0; p < placed.inside.size(); ++p) {
    placed.inside[p] =
        placed.inside[p] && r.depth.pixels[p] > 0 && r.normals.residual.pixels[p] >= 0;
    if (placed.inside[p]) {
      surface.height.pixels[p] = run.frame.perspective ? r.depth.pixels[p] : -r.depth.pixels[p];
    }
  }
  surface.summary.success = true;
  surface.summary.message = "the near-light loop's last surface";
  io::SurfaceFileOptions files;
  files.albedo = &r.normals.albedo;
  files.threads = common.threads;
  const io::SurfaceFiles written =
      io::WriteSurfaceFiles(out, "", surface, r.normals.normals, placed, run.frame, files);
  nlohmann::json passes = nlohmann::json::array();
  for (const near::NearPass& p : r.passes) {
    passes.push_back({{"kind", p.kind},
                      {"normals_moved_deg", p.change_deg},
                      {"distance_mm", p.distance},
                      {"seconds", p.seconds}});
  }
  nlohmann::json near{{"positions", d.files.near.positions_path},
                      {"camera", d.files.near.camera_path},
                      {"perspective", run.frame.perspective},
                      {"distance_mm", r.distance},
                      {"distance_from_images", r.distance_from_images},
                      {"passes", passes},
                      {"converged", r.converged},
                      {"last_change_deg", r.last_change_deg},
                      {"seconds", r.seconds},
                      {"mesh_triangles", written.triangles}};
  if (!d.depth_gt.pixels.empty() && d.depth_gt.width == r.depth.width &&
      d.depth_gt.height == r.depth.height) {
    double sq = 0;
    std::size_t n = 0;
    for (std::size_t p = 0; p < placed.inside.size(); ++p) {
      if (!placed.inside[p] || !(d.depth_gt.pixels[p] > 0)) continue;
      const double e = r.depth.pixels[p] - d.depth_gt.pixels[p];
      sq += e * e;
      ++n;
    }
    if (n > 0) near["depth_rmse_mm"] = std::sqrt(sq / n);
  }
  metrics["near_lights"] = near;
}

}  // namespace iphong::cli
