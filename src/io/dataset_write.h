// Writing photometric-stereo datasets in the DiLiGenT layout (io/dataset.h lists its files):
// what `iphong render` and iphong.save_dataset produce and io/dataset.h's LoadDataset reads back.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "io/dataset_text.h"
#include "io/output_folder.h"
#include "io/scene_file.h"
#include "render/renderer.h"

namespace iphong::io {

// "" when every light can go into a per-light dataset (the DiLiGenT layout has directions only),
// else which light cannot.
std::string CheckDatasetLights(const render::Scene& scene);

// A render's point lights as the near-light layout states them (io/near_capture.h): positions
// and LED axes in the main camera's frame (scene units as mm), each LED's anisotropy, the camera's
// intrinsics, and the directions toward the lights from the visible surface's mean point.
struct RenderedNearLights {
  std::vector<Vec3d> positions_mm, axes, directions;
  std::vector<double> anisotropy;
  CameraIntrinsics camera;
  bool leds = false;  // some anisotropy > 0: light_axes.txt and light_anisotropy.txt are written
  // An orthographic camera's frame has its origin moved along the axis to in front of every
  // light and every visible point (the layout's object is at z < 0): the depth to add.
  double depth_shift = 0;
};
RenderedNearLights NearLightsOf(const render::Scene& scene, const render::RenderOutput& output);

// A photometric-stereo dataset to write in the DiLiGenT layout.
struct DatasetToWrite {
  std::vector<const ImageF*> images;     // K, linear RGB, all the same size
  std::vector<Vec3d> light_directions;   // K
  std::vector<Vec3d> light_intensities;  // K (empty: all 1)
  const Mask* mask = nullptr;            // nullptr: the whole image
  const ImageF* normal_gt = nullptr;     // nullptr: no ground truth
  std::string material_json;             // "" = none
  // The fraction of images written, when set; called from the writing threads, one at a time.
  std::function<void(double)> progress;
  int threads = 0;  // images encoded at once (0: one per core)
};

// Writes 001.<ext> ... (as `settings` say), filenames.txt, light_directions.txt,
// light_intensities.txt, mask.png and, with ground truth, Normal_gt.mat, normals.exr and
// normals.png, plus material.json when given: the files `iphong render --per-light` and
// iphong.save_dataset write, which LoadDataset reads back. Throws std::invalid_argument for
// inconsistent sizes or counts.
void WriteDatasetFiles(OutputFolder& out, const std::string& prefix, const DatasetToWrite& d,
                       const OutputSettings& settings);

// Writes what `iphong render` produces into `out` under `prefix` ("" or "sub/"): with per_light,
// a DiLiGenT dataset (one image per light); otherwise image.<ext> with all lights. Ground truth
// either way. Nothing is visible until the caller commits `out`.
void WriteRenderOutput(OutputFolder& out, const std::string& prefix, const render::Scene& scene,
                       const render::RenderOptions& options, const render::RenderOutput& output,
                       const OutputSettings& settings, bool per_light,
                       const std::function<void(double)>& progress = {});

}  // namespace iphong::io
