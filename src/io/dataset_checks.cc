// What a loaded dataset's own numbers say about its files: the one-line description a run prints,
// and the checks that name a plausible mistake (an intensity file of another capture or read in
// another order, a mask drawn the wrong way round, photos repeated or left black) from the
// images' means inside the mask, before anything is solved.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <Eigen/QR>

#include "core/types.h"
#include "io/dataset.h"
#include "io/image_io.h"

namespace iphong::io {
namespace fs = std::filesystem;

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

}  // namespace iphong::io
