#include "io/dataset.h"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include <Eigen/QR>

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

[[noreturn]] void Fail(const fs::path& file, const std::string& message, int line = 0) {
  throw std::runtime_error(file.string() + (line > 0 ? ":" + std::to_string(line) : "") + ": " +
                           message);
}

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
          Fail(path, "is " + SizeText(h.width, h.height) + ", but " + reference + " is " +
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
      Fail(path, "not a finite number at pixel (" + std::to_string(p % normals.width) + ", " +
                     std::to_string(p / normals.width) + ")");
    }
    const double norm = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    if (norm == 0) continue;
    if (std::abs(norm - 1) > 0.05) {
      Fail(path, "is not a normal map: the vector at pixel (" + std::to_string(p % normals.width) +
                     ", " + std::to_string(p / normals.width) + ") has length " +
                     std::to_string(norm) + " (unit normals, 0 outside the object expected)");
    }
    ++unit;
  }
  if (unit == 0) Fail(path, "holds no normal (all zeros): empty or truncated");
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
    Fail(dir, fs::exists(dir, error) ? "not a folder (a dataset is a folder)" : "no such folder");
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
      Fail(d.files.mask_path, "is " + SizeText(file_mask.width, file_mask.height) +
                                  ", the images are " + SizeText(d.file_width, d.file_height) +
                                  " (" + d.filenames[0] + ")");
    }
    p.file_mask = cut(file_mask);
    d.mask = DownscaleMask(p.file_mask, capture.downscale);
    if (d.mask.count() == 0) {
      Fail(d.files.mask_path, p.file_mask.count() == 0
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
        Fail(truth, "is " + SizeText(d.normal_gt.width, d.normal_gt.height) + ", the images are " +
                        SizeText(d.file_width, d.file_height));
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
      Fail(truth, "is " + SizeText(d.depth_gt.width, d.depth_gt.height) + ", the images are " +
                      SizeText(d.file_width, d.file_height));
    }
    for (float v : d.depth_gt.pixels) {
      if (!std::isfinite(v) || v < 0)
        Fail(truth, "Depth_gt holds a value that is not a depth >= 0");
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
      Fail(path, std::to_string(bad) + " pixel(s) inside the mask are not finite (NaN or " +
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

std::string DescribeDataset(const Dataset& d, const std::string& ground_truth_note) {
  const CaptureFiles& f = d.files;
  const std::size_t k = f.names.size();
  auto base = [](const std::string& path) { return fs::path(path).filename().string(); };
  std::string text = std::to_string(k) + " images (" + f.layout + " layout, " + f.order + ": " +
                     (k == 1 ? f.names[0] : f.names.front() + " ... " + f.names.back()) + ")";
  if (!f.lights_path.empty()) {  // calibration reads no lights
    text += "; lights " + f.lights_path + " (" + f.lights_format + ")";
    text += "; intensities " + f.intensities_source;
  }
  text +=
      "; mask " + (f.mask_path.empty() ? std::string("none (the whole image)") : base(f.mask_path));
  if (!d.mask_reading.empty()) text += " (" + d.mask_reading + ")";
  text += "; encoding " + std::string(d.encoding.encoding == Encoding::kSrgb ? "srgb" : "linear") +
          " (" + d.encoding.reason + ")";
  if (d.mask.width > 0 && (d.mask.width != d.file_width || d.mask.height != d.file_height)) {
    text += "; " + SizeText(d.file_width, d.file_height) + " read as " +
            SizeText(d.mask.width, d.mask.height);
  }
  if (d.orientation != 1) {
    const bool swap = OrientationSwapsAxes(d.orientation);
    text += "; EXIF orientation " + std::to_string(d.orientation) + " of " + f.names[0] +
            " applied to every photo: " + DescribeOrientation(d.orientation) + " (stored " +
            SizeText(swap ? d.file_height : d.file_width, swap ? d.file_width : d.file_height) +
            ")";
  }
  text += "; ground truth " +
          (f.ground_truth_path.empty() ? std::string("none") : base(f.ground_truth_path));
  if (!f.ground_truth_path.empty() && !ground_truth_note.empty())
    text += " (" + ground_truth_note + ")";
  if (!f.skipped.empty()) {
    text += "; not read: ";
    for (std::size_t i = 0; i < f.skipped.size() && i < 4; ++i)
      text += (i ? ", " : "") + f.skipped[i];
    if (f.skipped.size() > 4) text += " and " + std::to_string(f.skipped.size() - 4) + " more";
  }
  return text;
}

std::string AllMaskedBlack(const Dataset& d) {
  if (d.image_counts.empty()) return "";
  for (const ImageCounts& c : d.image_counts) {
    if (c.pixels == 0 || c.black != c.pixels) return "";
  }
  return "every pixel inside the mask is black (0) in every image: no normal can be recovered" +
         std::string(d.files.mask_path.empty()
                         ? " (no image was exposed, or the files hold no picture)"
                         : " (a mask marking the background? Nonzero marks the object)");
}

namespace {

// Each image's mean inside the mask, and the same over its light's intensity.
struct MaskMeans {
  std::vector<double> mean, brightness;
};
MaskMeans MeansInsideMask(const Dataset& d) {
  MaskMeans m;
  for (std::size_t j = 0; j < d.image_counts.size(); ++j) {
    const ImageCounts& c = d.image_counts[j];
    const double e = j < d.light_intensities.size() ? d.light_intensities[j].mean() : 1.0;
    m.mean.push_back(c.pixels > 0 ? c.linear_sum / c.pixels : 0.0);
    m.brightness.push_back(e > 0 ? m.mean.back() / e : 0.0);
  }
  return m;
}

// A mask holding at least 95 % of the image's border pixels and leaving some pixels out: the
// background marked and the object left out, the usual way a mask is drawn the wrong way round
// (a photographed object rarely fills the frame to every edge around a hole).
bool MaskKeepsBorderAround(const Mask& m) {
  if (m.width < 3 || m.height < 3) return false;
  std::size_t border = 0, kept = 0;
  for (int x = 0; x < m.width; ++x) {
    kept += m.at(x, 0) + m.at(x, m.height - 1);
    border += 2;
  }
  for (int y = 1; y + 1 < m.height; ++y) {
    kept += m.at(0, y) + m.at(m.width - 1, y);
    border += 2;
  }
  return kept >= 0.95 * border && m.count() < m.inside.size();
}

}  // namespace

std::string DescribeIntensityFile(const Dataset& d) {
  char line[600];
  // The whole image follows Lambert's law as a pixel does: its mean over its light's intensity is
  // m_j / E_j ≈ b·L_j, b the mask's mean of albedo × normal (attached shadows aside). On the
  // shared captures with intensity files (DiLiGenT) that fit misses by 0.02–0.09 of the mean
  // brightness with the file and by 0.42–0.52 without it (E = 1); the same file shuffled misses
  // by 0.56–0.75 and inverted by 0.92–0.99. A file that fits worse than none does not belong to
  // the images, in this order. Point lights shine at each pixel from its own direction: not asked.
  if (!d.files.intensities_from_file || d.files.near.present() || d.image_counts.size() < 6 ||
      d.light_directions.size() != d.image_counts.size() ||
      d.light_intensities.size() != d.image_counts.size()) {
    return "";
  }
  const MaskMeans means = MeansInsideMask(d);
  const int k = static_cast<int>(d.image_counts.size());
  Eigen::MatrixX3d l(k, 3);
  const Eigen::VectorXd with_file = Eigen::Map<const Eigen::VectorXd>(means.brightness.data(), k);
  const Eigen::VectorXd without = Eigen::Map<const Eigen::VectorXd>(means.mean.data(), k);
  bool usable = true;
  for (int j = 0; j < k; ++j) {
    usable = usable && d.image_counts[j].pixels > 0;
    l.row(j) = d.light_directions[j].transpose();
  }
  if (!usable) return "";
  // One factorization of the lights serves every reading (up to 2K + 1 fits).
  const Eigen::ColPivHouseholderQR<Eigen::MatrixX3d> lights_qr(l);
  const auto misfit = [&](const Eigen::VectorXd& y) {
    const Eigen::Vector3d b = lights_qr.solve(y);
    const double scale = y.mean();
    return scale > 0 ? std::sqrt((y - l * b).squaredNorm() / k) / scale : 0.0;
  };
  const double file_misfit = misfit(with_file), plain_misfit = misfit(without);
  if (file_misfit > plain_misfit && file_misfit > kIntensityMisfitFloor) {
    std::snprintf(line, sizeof line,
                  "%s: the images' brightness follows their lights' directions worse with "
                  "these intensities than with none (misfit %.2f against %.2f of the mean): "
                  "are they in another order than the images, another capture's, or "
                  "inverted (exposure factors)?",
                  d.files.intensities_source.c_str(), file_misfit, plain_misfit);
    return line;
  }
  if (file_misfit > kIntensityOrderFloor) {
    // A file read a line off fits better than none (the intensities vary smoothly over the
    // dome) yet moves the normals 6-10 deg on DiLiGenT. The file's own re-readings (shifted
    // by s lines, reversed) are the likelier orders; the images were taken in one of them, so
    // the reading that fits best is the one to name when it beats the file as listed.
    Eigen::VectorXd intensity(k);
    for (int j = 0; j < k; ++j) intensity(j) = d.light_intensities[j].mean();
    double best = file_misfit;
    int best_shift = 0;
    bool best_reversed = false;
    for (const bool reversed : {false, true}) {
      for (int s = 0; s < k; ++s) {
        if (s == 0 && !reversed) continue;
        Eigen::VectorXd y(k);
        for (int j = 0; j < k; ++j) {
          const int line_index = reversed ? (k - 1 - j + s) % k : (j + s) % k;
          y(j) = intensity(line_index) > 0 ? without(j) / intensity(line_index) : 0.0;
        }
        const double m = misfit(y);
        if (m < best) best = m, best_shift = s, best_reversed = reversed;
      }
    }
    if (best * kIntensityOrderMargin < file_misfit) {
      char reading[120];
      const int shift = best_shift > k / 2 ? best_shift - k : best_shift;
      if (best_reversed) {
        std::snprintf(reading, sizeof reading, "in reverse order (image 1 on line %d)",
                      (k - 1 + best_shift) % k + 1);
      } else {
        std::snprintf(reading, sizeof reading, "%d line%s %s (image 1 on line %d)", std::abs(shift),
                      std::abs(shift) == 1 ? "" : "s", shift > 0 ? "further down" : "further up",
                      best_shift + 1);
      }
      std::snprintf(line, sizeof line,
                    "%s: the images' brightness follows their lights' directions better with "
                    "these intensities read %s than as listed (misfit %.3f against %.3f of the "
                    "mean): is the file a line off from the images (a header line, a light "
                    "missing at the top, images numbered from 0 and lights from 1)?",
                    d.files.intensities_source.c_str(), reading, best, file_misfit);
      return line;
    }
  }
  return "";
}

std::string DescribeImageCounts(const Dataset& d) {
  std::size_t worst_saturated = 0, worst_black = 0, clipped_images = 0, black_images = 0;
  double saturated_fraction = 0, black_fraction = 0;
  for (std::size_t j = 0; j < d.image_counts.size(); ++j) {
    const ImageCounts& c = d.image_counts[j];
    if (c.pixels == 0) continue;
    const double s = double(c.saturated) / c.pixels, b = double(c.black) / c.pixels;
    clipped_images += s > 0.01;
    black_images += b > 0.1;  // cast shadows alone reach a few percent
    if (s > saturated_fraction) saturated_fraction = s, worst_saturated = j;
    if (b > black_fraction) black_fraction = b, worst_black = j;
  }
  std::string text;
  char line[512];  // file names are part of it
  std::size_t turned = 0, first_turned = 0;
  for (std::size_t j = 0; j < d.image_counts.size(); ++j) {
    if (d.image_counts[j].pixels > 0 && d.image_counts[j].orientation != d.orientation) {
      if (turned++ == 0) first_turned = j;
    }
  }
  if (turned > 0) {
    text = std::to_string(turned) + " of " + std::to_string(d.image_counts.size()) +
           " images state another EXIF orientation than " + d.filenames[0] + " (" +
           d.filenames[first_turned] + ": " +
           DescribeOrientation(d.image_counts[first_turned].orientation) + "); all are read as " +
           d.filenames[0] +
           " is, since a camera on a mount does not turn between shots: check that the photos "
           "line up";
  }
  if (clipped_images > 0) {
    std::snprintf(line, sizeof line,
                  "%zu of %zu images have more than 1%% of the mask clipped at the format's "
                  "maximum (most: %s, %.1f%%); clipped values are left out of the fit",
                  clipped_images, d.image_counts.size(), d.filenames[worst_saturated].c_str(),
                  100 * saturated_fraction);
    text += (text.empty() ? "" : "; ") + std::string(line);
  }
  if (black_images > 0) {
    std::snprintf(line, sizeof line,
                  "%zu of %zu images are black (0) on more than 10%% of the mask (most: %s, "
                  "%.1f%%): under-exposed, or lights the object does not face",
                  black_images, d.image_counts.size(), d.filenames[worst_black].c_str(),
                  100 * black_fraction);
    text += (text.empty() ? "" : "; ") + std::string(line);
    if (d.files.mask_path.empty()) {
      text += " (there is no mask: the background counts; --mask)";
    } else if (MaskKeepsBorderAround(d.mask)) {
      text +=
          " (the mask keeps the image's border and leaves out a region inside it: drawn the "
          "wrong way round? Nonzero marks the object)";
    }
  }
  // Each image's mean inside the mask over its light's intensity is its light's mean shading
  // times the albedo: on every shared capture (DiLiGenT, UW with its chrome sphere, the rendered
  // bunny) the brightest image is within 1.41 times the median's. A hundred times is no shading:
  // a photo at another exposure, or stored in other units (0–255 among 0–1).
  const std::vector<double> brightness = MeansInsideMask(d).brightness;
  if (!brightness.empty()) {
    std::vector<double> sorted = brightness;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median = sorted[sorted.size() / 2];
    std::size_t bright = 0, brightest = 0, negative = 0, first_negative = 0;
    for (std::size_t j = 0; j < brightness.size(); ++j) {
      if (median > 0 && brightness[j] > kBrightImageRatio * median) {
        if (bright++ == 0 || brightness[j] > brightness[brightest]) brightest = j;
      }
      if (d.image_counts[j].linear_sum < 0 && negative++ == 0) first_negative = j;
    }
    if (bright > 0) {
      std::snprintf(line, sizeof line,
                    "%zu of %zu images are more than %g times as bright as the median image, "
                    "after their lights' intensities (most: %s, %.3g times): a photo at another "
                    "exposure, or stored in other units (0-255 among 0-1)? Give its intensity "
                    "(--intensities) or convert it",
                    bright, brightness.size(), kBrightImageRatio, d.filenames[brightest].c_str(),
                    brightness[brightest] / median);
      text += (text.empty() ? "" : "; ") + std::string(line);
    }
    if (negative > 0) {
      std::snprintf(line, sizeof line,
                    "%zu of %zu images are negative on average inside the mask (first: %s): a "
                    "black level subtracted twice, or an offset? Light only adds; these values "
                    "are read as dark",
                    negative, brightness.size(), d.filenames[first_negative].c_str());
      text += (text.empty() ? "" : "; ") + std::string(line);
    }
  }
  if (std::string file = DescribeIntensityFile(d); !file.empty()) {
    text += (text.empty() ? "" : "; ") + file;
  }
  // Images identical inside the mask: the first of each group and how many repeat it.
  std::size_t repeats = 0, groups = 0, first_a = 0, first_b = 0;
  std::vector<bool> counted(d.image_counts.size(), false);
  // Images black (or clipped) at every pixel are alike by nature, not copies: a dome's lights
  // behind the object; the black and clipped counts speak for them.
  const auto blank = [&](std::size_t j) {
    const ImageCounts& c = d.image_counts[j];
    return c.pixels == 0 || c.black == c.pixels || c.saturated == c.pixels;
  };
  for (std::size_t a = 0; a < d.image_counts.size(); ++a) {
    if (counted[a] || blank(a)) continue;
    std::size_t same = 0;
    for (std::size_t b = a + 1; b < d.image_counts.size(); ++b) {
      // One file listed twice is named by the capture's own warning (capture.cc).
      if (counted[b] || d.image_counts[b].pixels != d.image_counts[a].pixels ||
          d.image_counts[b].masked_hash != d.image_counts[a].masked_hash ||
          d.filenames[b] == d.filenames[a]) {
        continue;
      }
      counted[b] = true;
      if (same++ == 0 && groups == 0) first_a = a, first_b = b;
    }
    if (same > 0) ++groups, repeats += same;
  }
  if (repeats > 0 && repeats + 1 == d.image_counts.size()) {
    std::snprintf(line, sizeof line,
                  "all %zu images are identical inside the mask: the light did not change between "
                  "the photographs, or one photo was saved under every name",
                  d.image_counts.size());
    text += (text.empty() ? "" : "; ") + std::string(line);
  } else if (repeats > 0) {
    std::snprintf(line, sizeof line,
                  "%zu of %zu images repeat another pixel for pixel inside the mask (%s and %s "
                  "are identical): one photo saved under two names? Each light needs its own",
                  repeats, d.image_counts.size(), d.filenames[first_a].c_str(),
                  d.filenames[first_b].c_str());
    text += (text.empty() ? "" : "; ") + std::string(line);
  }
  return text;
}

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
