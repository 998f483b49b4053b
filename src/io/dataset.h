// Photometric-stereo datasets: the images of a capture under known lights, read from a folder in
// any layout io/capture.h finds (DiLiGenT, UW, RTI .lp, a plain folder). The DiLiGenT layout
// (SPEC.md), which iphong writes:
//   filenames.txt            one image file name per line
//   light_directions.txt     one "lx ly lz" per line (unit, surface → light, camera frame)
//   light_intensities.txt    one "r g b" per line (absent = all ones)
//   mask.png                 nonzero = object (absent = whole image)
//   Normal_gt.mat / normal.txt   optional ground truth
//   material.json            optional known coefficients
// iphong also writes normals.exr, depth.exr, albedo.exr and render.json (how it was rendered):
// io/dataset_write.h; Normal_gt.mat is read and written by io/normal_mat.h.
#pragma once

#include <cstdint>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/resources.h"
#include "io/capture.h"
#include "io/dataset_text.h"
#include "solve/photometric_data.h"

namespace iphong::io {

// Per image, over the mask at the files' resolution: pixels whose stored value is the format's
// maximum in some channel (clipped: the true value is unknown) and pixels zero in every channel.
struct ImageCounts {
  std::size_t pixels = 0, saturated = 0, black = 0;
  int orientation = 1;  // the EXIF orientation the file states (io/image_io.h)
  // FNV-1a of the stored values inside the mask, row by row: equal for images identical there.
  std::uint64_t masked_hash = 14695981039346656037ull;
  // Σ of the linear values' channel mean inside the mask: the image's mean brightness × pixels.
  double linear_sum = 0;
  bool integer_codes = true;  // the file's own sample type: only integer codes clip at 1
};

struct Dataset {
  std::string directory;
  CaptureFiles files;                   // what was found where
  EncodingChoice encoding;              // how the image values were read
  int file_width = 0, file_height = 0;  // the files' size as displayed, before --crop/--downscale
  // The EXIF orientation every photo is read under: the one the first states. A camera on a mount
  // does not turn between shots, so photos that state another are read as the first is (their
  // stored pixels line up; DescribeImageCounts says so).
  int orientation = 1;
  std::vector<ImageCounts> image_counts;  // per image, filled as the images are read
  std::vector<std::string> filenames;
  std::vector<ImageF> images;            // linear float RGB, one per light
  std::vector<Vec3d> light_directions;   // unit
  std::vector<Vec3d> light_intensities;  // RGB
  Mask mask;
  std::string mask_reading;  // how the mask file was read when not as nonzero colour (ReadMask)
  ImageF normal_gt;          // 3 channels; empty when the dataset has none
  // Near-light captures: Depth_gt.mat (mm along the optical axis, 0 outside; 1 channel), empty
  // when absent (or under --downscale, which would average depths across edges).
  ImageF depth_gt;
  std::optional<DatasetMaterial> material;
  std::vector<std::string> warnings;  // e.g. light directions that were not unit

  int width() const { return mask.width; }
  int height() const { return mask.height; }
};

struct DatasetLoadOptions {
  CaptureOptions capture;  // light file, mask, encoding, crop, downscale
  bool load_images = true;
  bool load_ground_truth = true;
  int threads = 0;
  MemoryLimit memory;  // checked before the images are decoded
  // Called with the fraction of images decoded, from the decoding threads (may be concurrent).
  std::function<void(double)> progress;
};

// One line saying what was read: how many images, from which list or in which order, the light
// file, the intensities, the mask, the encoding and why, the size after --crop/--downscale, the
// ground truth (followed by `ground_truth_note` in brackets when one is given and there is one).
std::string DescribeDataset(const Dataset& dataset, const std::string& ground_truth_note = "");

// "" or one line on the images with clipped pixels (over 1% of the mask) or black ones (over 10%:
// cast shadows alone make a few percent), on images far brighter than the rest for their lights'
// intensities or negative on average, on an intensity file the images' brightness contradicts
// (distant lights), and on images identical inside the mask (one photo under
// two names, or all of them: `normals` then refuses in its plan).
std::string DescribeImageCounts(const Dataset& dataset);
// "" or, for intensities read from a file under distant lights, why the images contradict it:
// each image's mean inside the mask over its light's intensity fits b·L_j (Lambert's law for
// the whole mask) worse than with no file, or better with the file read in another order (shifted
// by whole lines, reversed). Part of DescribeImageCounts; `normals --estimate-intensities` asks
// it to decide whether the file is the one to trust.
std::string DescribeIntensityFile(const Dataset& dataset);
// "" or, when every image is black (0) at every pixel inside the mask (and there is one), why
// nothing can be recovered: `normals` refuses such a capture (a mask marking the background).
std::string AllMaskedBlack(const Dataset& dataset);

// An image this many times as bright as the median one (each over its light's intensity) is
// named by DescribeImageCounts: no light's shading does that.
constexpr double kBrightImageRatio = 100;
// DescribeImageCounts names an intensity file only when the images' fit with it misses by more
// than this share of their mean brightness (and by more than without it): a file of nearly equal
// intensities changes both fits alike, and noise in a few images is not a wrong file.
constexpr double kIntensityMisfitFloor = 0.1;
// An intensity file that fits better than none is still named when one of its own re-readings
// (shifted by whole lines, or reversed) fits its images this many times better. On DiLiGenT's
// seven shared captures the file as shipped fits best of its 192 readings, the next by a factor
// 1.6 to 7; shifted by one line, the file as shipped fits better by 1.6 to 22.
constexpr double kIntensityOrderMargin = 1.25;
// A file whose images follow Lambert's law within this share of their mean brightness is not
// questioned: its readings differ too little to matter (a rendered bunny's exact file: 0.018).
constexpr double kIntensityOrderFloor = 0.03;

// Reads a dataset directory. Throws std::runtime_error whose one-line message names the file
// (and the line for text files): missing or short light files, NaN, zero intensities, image
// count or size mismatches (the mask and the ground truth are checked against the first image's
// header before anything large is read), unreadable images, bad JSON, ground truth that is not a
// map of unit normals; ResourceError when the images would not fit in `options.memory`.
Dataset LoadDataset(const std::string& directory, const DatasetLoadOptions& options = {});

// The dataset without its images, plus the masked pixels of every image gathered as the images
// are decoded (in parallel, one image per thread at a time): memory is K × masked pixels × 3
// floats instead of K full images. Same errors as LoadDataset.
struct ObservationSet {
  Dataset dataset;  // images left empty
  solve::PhotometricData observations;
};
ObservationSet LoadObservations(const std::string& directory,
                                const DatasetLoadOptions& options = {});

}  // namespace iphong::io
