#include "io/dataset.h"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "core/errors.h"
#include "core/image_ops.h"
#include "core/parallel.h"
#include "io/capture.h"
#include "io/dataset_internal.h"
#include "io/dataset_text.h"
#include "io/files.h"
#include "io/json_reader.h"
#include "io/normal_mat.h"
#include "io/output_folder.h"

namespace iphong::io {
namespace fs = std::filesystem;
namespace {

using internal::ToRgb;

// One image of a dataset, refused from its header when its size is not the dataset's
// (`reference` names the file that set it).
ImageF ReadDatasetImage(const std::string& path, int width, int height, int orientation,
                        const std::string& reference, const MemoryLimit& memory,
                        ImageCounts* counts) {
  return ToRgb(ReadImage(
      path, memory,
      [&](const ImageHeader& h) {
        if (counts) {
          counts->orientation = h.orientation;
          counts->integer_codes = !h.is_float;
        }
        if (h.width != width || h.height != height) {
          FailInput(path, "is " + SizeText(h.width, h.height) + ", but " + reference + " is " +
                              SizeText(width, height));
        }
      },
      orientation));
}

// Ground truth must be a map of unit normals (0 outside the object), not zeros or noise.
void CheckNormalMap(const ImageF& normals, const std::string& path) {
  std::size_t unit = 0;
  for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
    const float* n = normals.pixels.data() + 3 * p;
    if (!std::isfinite(n[0]) || !std::isfinite(n[1]) || !std::isfinite(n[2])) {
      FailInput(path, "not a finite number at pixel (" + std::to_string(p % normals.width) + ", " +
                          std::to_string(p / normals.width) + ")");
    }
    const double norm = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    if (norm == 0) continue;
    if (std::abs(norm - 1) > 0.05) {
      FailInput(path, "is not a normal map: the vector at pixel (" +
                          std::to_string(p % normals.width) + ", " +
                          std::to_string(p / normals.width) + ") has length " +
                          std::to_string(norm) + " (unit normals, 0 outside the object expected)");
    }
    ++unit;
  }
  if (unit == 0) FailInput(path, "holds no normal (all zeros): empty or truncated");
}

}  // namespace

namespace internal {

ImageF ToRgb(ImageF image) {
  if (image.channels == 3) return image;
  ImageF rgb(image.width, image.height, 3);
  for (std::size_t p = 0; p < image.pixel_count(); ++p) {
    for (int c = 0; c < 3; ++c) {
      rgb.pixels[3 * p + c] = image.pixels[p * image.channels + (image.channels >= 3 ? c : 0)];
    }
  }
  return rgb;
}

Prepared Prepare(const std::string& directory, const DatasetLoadOptions& options) {
  const fs::path dir(directory);
  std::error_code error;
  if (!fs::is_directory(dir, error)) {
    FailInput(dir,
              fs::exists(dir, error) ? "not a folder (a dataset is a folder)" : "no such folder");
  }
  FinishInterruptedCommit(directory);  // an iphong render output cut off while committing
  Prepared p;
  Dataset& d = p.d;
  d.directory = directory;
  d.files = FindCapture(directory, options.capture);
  d.filenames = d.files.names;
  d.light_directions = d.files.light_directions;
  d.light_intensities = d.files.light_intensities;
  d.warnings = d.files.warnings;
  if (!d.files.material_path.empty()) {
    d.material = ParseMaterialJson(ReadTextFile(d.files.material_path), d.files.material_path);
  }

  // The images' size from the first one's header, so the mask and the ground truth are checked
  // against it before anything large is read.
  const std::string& first = d.files.paths[0];
  const bool have_first = options.load_images || fs::exists(first, error);
  if (have_first) {
    const StoredEncoding stored = ReadStoredEncoding(first);  // its header too: one open
    d.file_width = stored.header.width;
    d.file_height = stored.header.height;
    d.orientation = stored.header.orientation;
    d.encoding = ChooseEncoding(d.files, options.capture, stored);
  } else {
    d.encoding = ChooseEncoding(d.files, options.capture, StoredEncoding{});
  }
  p.srgb = d.encoding.encoding == Encoding::kSrgb;
  const CaptureOptions& capture = options.capture;
  if (capture.crop.width > 0) {
    p.crop = capture.crop;
    if (have_first) {
      if (std::string m = CheckRect(p.crop, d.file_width, d.file_height); !m.empty()) {
        throw std::invalid_argument(first + ": " + m);
      }
    }
  }
  // Every cut is checked against what it cuts: without the first image (ground truth only) the
  // crop was not checked above.
  auto check_crop = [&](int width, int height, const std::string& path) {
    if (std::string m = CheckRect(p.crop, width, height); !m.empty()) {
      throw std::invalid_argument(path + ": " + m);
    }
  };
  auto cut = [&](const Mask& m) {
    if (p.crop.width == 0) return m;
    check_crop(m.width, m.height, d.files.mask_path);
    return CropMask(m, p.crop);
  };
  int width = 0, height = 0;
  if (have_first) {
    TransformedSize(d.file_width, d.file_height, p.crop.width > 0 ? &p.crop : nullptr,
                    capture.downscale, &width, &height);
    if (width < 1 || height < 1) {
      throw std::invalid_argument(first + ": " + SizeText(d.file_width, d.file_height) +
                                  " is smaller than one pixel after --downscale " +
                                  std::to_string(capture.downscale));
    }
  }

  if (!d.files.mask_path.empty()) {
    const Mask file_mask = ReadMask(d.files.mask_path, options.memory, &d.mask_reading);
    if (have_first && (file_mask.width != d.file_width || file_mask.height != d.file_height)) {
      FailInput(d.files.mask_path, "is " + SizeText(file_mask.width, file_mask.height) +
                                       ", the images are " + SizeText(d.file_width, d.file_height) +
                                       " (" + d.filenames[0] + ")");
    }
    p.file_mask = cut(file_mask);
    d.mask = DownscaleMask(p.file_mask, capture.downscale);
    if (d.mask.count() == 0) {
      FailInput(d.files.mask_path, p.file_mask.count() == 0
                                       ? "selects no pixel (all zero; nonzero = object)"
                                       : "selects no pixel after --crop/--downscale");
    }
  } else if (have_first) {
    p.file_mask = Mask(p.crop.width > 0 ? p.crop.width : d.file_width,
                       p.crop.width > 0 ? p.crop.height : d.file_height, true);
    d.mask = Mask(width, height, true);
  }

  if (options.load_ground_truth && !d.files.ground_truth_path.empty()) {
    const std::string& truth = d.files.ground_truth_path;
    if (truth.size() >= 4 && truth.compare(truth.size() - 4, 4, ".mat") == 0) {
      d.normal_gt = ReadNormalMat(truth, "Normal_gt");
    } else if (have_first) {
      d.normal_gt = ParseNormalText(ReadTextFile(truth, std::uint64_t{8} << 30), truth,
                                    d.file_width, d.file_height);
    }
    if (!d.normal_gt.pixels.empty()) {
      if (have_first &&
          (d.normal_gt.width != d.file_width || d.normal_gt.height != d.file_height)) {
        FailInput(truth, "is " + SizeText(d.normal_gt.width, d.normal_gt.height) +
                             ", the images are " + SizeText(d.file_width, d.file_height));
      }
      CheckNormalMap(d.normal_gt, truth);
      if (p.crop.width > 0) {
        check_crop(d.normal_gt.width, d.normal_gt.height, truth);
        d.normal_gt = CropImage(d.normal_gt, p.crop);
      }
      d.normal_gt = DownscaleNormals(d.normal_gt, capture.downscale);
    }
  }
  if (options.load_ground_truth && !d.files.near.depth_gt_path.empty() && capture.downscale == 1) {
    const std::string& truth = d.files.near.depth_gt_path;
    d.depth_gt = ReadMatImage(truth, "Depth_gt", 1);
    if (have_first && (d.depth_gt.width != d.file_width || d.depth_gt.height != d.file_height)) {
      FailInput(truth, "is " + SizeText(d.depth_gt.width, d.depth_gt.height) + ", the images are " +
                           SizeText(d.file_width, d.file_height));
    }
    for (float v : d.depth_gt.pixels) {
      if (!std::isfinite(v) || v < 0)
        FailInput(truth, "Depth_gt holds a value that is not a depth >= 0");
    }
    if (p.crop.width > 0) {
      check_crop(d.depth_gt.width, d.depth_gt.height, truth);
      d.depth_gt = CropImage(d.depth_gt, p.crop);
    }
  }
  p.counted_pixels = p.file_mask.count();
  d.image_counts.assign(d.filenames.size(), {});
  return p;
}

ImageF WorkingRows(const Prepared& p, ImageF rows, int skip, int count, int file_y0, int downscale,
                   ImageCounts* counts, const std::string& path) {
  rows = ToRgb(std::move(rows));
  if (p.crop.width > 0 || skip > 0 || count != rows.height) {
    rows = CropImage(rows, {p.crop.width > 0 ? p.crop.x : 0, skip,
                            p.crop.width > 0 ? p.crop.width : rows.width, count});
  }
  {
    // Every reader of captures (CLI, bands, Python, calibration) meets a NaN here, named, rather
    // than in whatever it computes from it.
    const std::size_t first = static_cast<std::size_t>(file_y0) * rows.width;
    std::size_t bad = 0, at = 0;
    for (std::size_t q = 0; q < rows.pixel_count(); ++q) {
      if (!p.file_mask.inside[first + q]) continue;
      const float* v = rows.pixels.data() + 3 * q;
      if (std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])) continue;
      if (bad++ == 0) at = q;
    }
    if (bad > 0) {
      const int x0 = p.crop.width > 0 ? p.crop.x : 0, y0 = p.crop.width > 0 ? p.crop.y : 0;
      FailInput(path, std::to_string(bad) + " pixel(s) inside the mask are not finite (NaN or " +
                          "infinite; the first at column " + std::to_string(x0 + at % rows.width) +
                          ", row " + std::to_string(y0 + file_y0 + at / rows.width) + ")");
    }
  }
  if (counts) {
    // Saturation is a property of the stored code values: counted before any averaging.
    const std::size_t first = static_cast<std::size_t>(file_y0) * rows.width;
    for (std::size_t q = 0; q < rows.pixel_count(); ++q) {
      if (!p.file_mask.inside[first + q]) continue;
      const float* v = rows.pixels.data() + 3 * q;
      if (v[0] == 0 && v[1] == 0 && v[2] == 0) ++counts->black;
      if (counts->integer_codes && (v[0] >= 1 || v[1] >= 1 || v[2] >= 1)) ++counts->saturated;
      unsigned char bytes[3 * sizeof(float)];
      std::memcpy(bytes, v, sizeof bytes);
      for (unsigned char byte : bytes)
        counts->masked_hash = (counts->masked_hash ^ byte) * 1099511628211ull;
    }
    counts->pixels = p.counted_pixels;
  }
  if (p.srgb) LinearizeSrgb(rows);
  if (counts) {
    const std::size_t first = static_cast<std::size_t>(file_y0) * rows.width;
    for (std::size_t q = 0; q < rows.pixel_count(); ++q) {
      if (!p.file_mask.inside[first + q]) continue;
      const float* v = rows.pixels.data() + 3 * q;
      counts->linear_sum += (double(v[0]) + v[1] + v[2]) / 3;
    }
  }
  return DownscaleImage(rows, downscale);
}

}  // namespace internal

namespace {

using internal::Prepare;
using internal::Prepared;

// Image j at the working size: decoded, cropped, counted, linearized, downscaled.
ImageF ReadWorkingImage(const Prepared& p, std::size_t j, const std::string& reference,
                        const DatasetLoadOptions& options, ImageCounts* counts) {
  const Dataset& d = p.d;
  const int rows = p.crop.width > 0 ? p.crop.height : d.file_height;
  return internal::WorkingRows(p,
                               ReadDatasetImage(d.files.paths[j], d.file_width, d.file_height,
                                                d.orientation, reference, options.memory, counts),
                               p.crop.width > 0 ? p.crop.y : 0, rows, 0, options.capture.downscale,
                               counts, d.files.paths[j]);
}

}  // namespace

Dataset LoadDataset(const std::string& directory, const DatasetLoadOptions& options) {
  Prepared p = Prepare(directory, options);
  Dataset& d = p.d;
  if (options.load_images) {
    const std::size_t k = d.filenames.size();
    const int width = d.mask.width, height = d.mask.height;
    RequireMemory(options.memory,
                  static_cast<double>(k) * width * height * 3 * sizeof(float) +
                      2.0 * d.file_width * d.file_height * 3 * sizeof(float),
                  directory + ": " + std::to_string(k) + " images of " + SizeText(width, height));
    d.images.resize(k);
    std::vector<std::string> errors(k);
    ParallelFor(0, k, 1, options.threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        try {
          d.images[i] = ReadWorkingImage(p, i, d.filenames[0], options, &d.image_counts[i]);
        } catch (const std::exception& ex) {
          errors[i] = ex.what();
        }
      }
    });
    for (const std::string& message : errors)
      if (!message.empty()) throw std::runtime_error(message);
  }
  return std::move(p.d);
}

}  // namespace iphong::io

namespace iphong::io {

ObservationSet LoadObservations(const std::string& directory, const DatasetLoadOptions& options) {
  DatasetLoadOptions meta_options = options;
  meta_options.load_images = false;
  ObservationSet set;
  Prepared p = Prepare(directory, meta_options);
  Dataset& d = p.d;
  const std::size_t k = d.filenames.size();
  if (d.mask.width == 0) {  // the first image was not there to size the whole-image mask
    RequireRegularFile(d.files.paths[0]);
  }
  const int w = d.mask.width, h = d.mask.height;
  // The observations, plus one decoded image (and the decoder's buffer) per thread.
  const double threads = std::min<double>(ResolveThreads(options.threads), k);
  RequireMemory(options.memory,
                (static_cast<double>(k) * d.mask.count() * 3 +
                 threads * 2.0 * d.file_width * d.file_height * 4) *
                    sizeof(float),
                directory + ": " + std::to_string(k) + " images of " + SizeText(w, h));
  solve::PhotometricData& data = set.observations;
  data = solve::ObservationLayout(w, h, d.mask, d.light_directions, d.light_intensities);
  const std::string reference =
      d.files.mask_path.empty() ? d.filenames[0] : fs::path(d.files.mask_path).filename().string();
  std::vector<std::string> errors(k);
  std::atomic<std::size_t> decoded{0};
  ParallelFor(0, k, 1, options.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t j = b; j < e; ++j) {
      try {
        const ImageF image = ReadWorkingImage(p, j, reference, options, &d.image_counts[j]);
        if (options.progress) options.progress(double(++decoded) / k);
        if (auto m = solve::GatherImage(data, static_cast<int>(j), image.pixels.data());
            !m.empty()) {
          errors[j] = d.files.paths[j] + ": " + m;
        }
      } catch (const std::exception& ex) {
        errors[j] = ex.what();
      }
    }
  });
  // The first failure in light order, whichever thread met it first.
  for (const std::string& error : errors)
    if (!error.empty()) throw std::runtime_error(error);
  if (auto m = data.Validate(); !m.empty()) throw std::runtime_error(directory + ": " + m);
  set.dataset = std::move(p.d);
  return set;
}

}  // namespace iphong::io
