#include "io/visualize.h"

#include <filesystem>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "integrate/frame_check.h"
#include "io/dataset.h"
#include "io/files.h"
#include "io/image_io.h"
#include "io/normal_mat.h"
#include "render/preview.h"

namespace iphong::io {

ImageF NormalMapPicture(const ImageF& normals, const Mask& mask, bool directx) {
  ImageF picture(normals.width, normals.height, 3);
  for (std::size_t p = 0; p < mask.inside.size(); ++p) {
    if (!mask.inside[p]) continue;
    for (int c = 0; c < 3; ++c) {
      float v = normals.pixels[3 * p + c];
      if (directx && c == 1) v = -v;
      picture.pixels[3 * p + c] = 0.5f * (v + 1);
    }
  }
  return picture;
}

ImageF NormalsFromPicture(const ImageF& picture, bool directx, Mask* mask) {
  if (picture.channels < 3) throw std::invalid_argument("a normal-map picture needs 3 channels");
  ImageF normals(picture.width, picture.height, 3);
  *mask = Mask(picture.width, picture.height, false);
  for (std::size_t p = 0; p < picture.pixel_count(); ++p) {
    const float* v = picture.pixels.data() + p * picture.channels;
    if (v[0] == 0 && v[1] == 0 && v[2] == 0) continue;
    Vec3f n(2 * v[0] - 1, 2 * v[1] - 1, 2 * v[2] - 1);
    if (directx) n.y() = -n.y();
    if (!(n.norm() > 0.1f)) continue;
    n.normalize();
    std::copy(n.data(), n.data() + 3, normals.pixels.data() + 3 * p);
    mask->inside[p] = 1;
  }
  return normals;
}

ImageF ReadNormalMap(const std::string& path, bool directx, Mask* mask, const MemoryLimit& memory) {
  const std::string ext = LowerExtension(path);
  if (ext == ".mat") return ReadNormalMat(path, "Normal_gt");
  ImageF image = ReadImage(path, memory);
  if (image.channels < 3) {
    throw std::runtime_error(path + ": has " + std::to_string(image.channels) +
                             " channel(s); a normal map needs 3 (x, y, z)");
  }
  if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tga" || ext == ".bmp") {
    // Pictures store (n + 1)/2; ReadImage undoes no transfer curve, and a normal picture has none.
    Mask ignored;
    return NormalsFromPicture(image, directx, mask ? mask : &ignored);
  }
  if (image.channels == 3) return image;
  ImageF xyz(image.width, image.height, 3);
  for (std::size_t p = 0; p < image.pixel_count(); ++p)
    for (int c = 0; c < 3; ++c) xyz.pixels[3 * p + c] = image.pixels[p * image.channels + c];
  return xyz;
}

Mask RequireUnitNormals(const ImageF& normals, const Mask* mask, const std::string& path,
                        std::size_t* facing_away_out) {
  if (normals.channels != 3) throw std::runtime_error(path + ": a normal map needs 3 channels");
  if (mask && (mask->width != normals.width || mask->height != normals.height)) {
    throw std::runtime_error(path + ": is " + SizeText(normals.width, normals.height) +
                             ", the mask " + SizeText(mask->width, mask->height));
  }
  std::size_t not_finite = 0, not_unit = 0, first_nan = 0, first_bad = 0, facing_away = 0;
  float bad_length = 0;
  Mask present(normals.width, normals.height, false);
  for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
    if (mask && !mask->inside[p]) continue;
    const float* v = normals.pixels.data() + 3 * p;
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
      if (not_finite++ == 0) first_nan = p;
      continue;
    }
    if (v[0] == 0 && v[1] == 0 && v[2] == 0) continue;
    const float length = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (std::abs(length - 1) > 0.01f) {
      if (not_unit++ == 0) first_bad = p, bad_length = length;
      continue;
    }
    present.inside[p] = 1;
    facing_away += v[2] < 0;
  }
  auto where = [&](std::size_t p) {
    return "column " + std::to_string(p % normals.width) + ", row " +
           std::to_string(p / normals.width);
  };
  if (not_finite > 0) {
    throw std::runtime_error(path + ": " + std::to_string(not_finite) +
                             " normals are not finite (NaN or infinite; the first at " +
                             where(first_nan) + "): a normal map holds unit vectors, 0 where " +
                             "there is none");
  }
  if (not_unit > 0) {
    char length[32];
    std::snprintf(length, sizeof length, "%.4g", bad_length);
    throw std::runtime_error(path + ": " + std::to_string(not_unit) +
                             " normals are not unit length (|n| = " + length + " at " +
                             where(first_bad) + "): a normal map holds unit vectors");
  }
  if (facing_away_out) *facing_away_out = facing_away;
  return present;
}

std::vector<std::string> CheckNormalMap(const ImageF& normals, const Mask* mask,
                                        const std::string& path) {
  std::size_t facing_away = 0;
  const Mask present = RequireUnitNormals(normals, mask, path, &facing_away);
  std::vector<std::string> warnings;
  const std::size_t count = present.count();
  if (count == 0) return warnings;
  // Most normals facing away is a frame with z negated, no reading of the image plane: the
  // commands refuse or warn about it themselves.
  if (2 * facing_away > count) return warnings;
  const integrate::FrameCheckResult frame = integrate::CheckNormalFrame(normals, present);
  if (!frame.message.empty()) {
    warnings.push_back(path + ": the normals look like another frame: " + frame.message +
                       "; iphong's frame has x right, y up toward row 0, z toward the camera" +
                       " (a DirectX-convention picture has y negated)");
  }
  return warnings;
}

double ErrorMapScale(const ImageF& error_deg, const Mask& mask) {
  std::vector<float> errors;
  for (std::size_t p = 0; p < mask.inside.size(); ++p) {
    if (mask.inside[p] && std::isfinite(error_deg.pixels[p])) errors.push_back(error_deg.pixels[p]);
  }
  if (errors.empty()) return 1;
  const std::size_t k = static_cast<std::size_t>(0.95 * (errors.size() - 1));
  std::nth_element(errors.begin(), errors.begin() + k, errors.end());
  const double top = std::max<double>(errors[k], 1e-6);
  const double decade = std::pow(10.0, std::floor(std::log10(top)));
  for (double step : {1.0, 2.0, 5.0, 10.0}) {
    if (step * decade >= top * (1 - 1e-9)) return step * decade;
  }
  return 10 * decade;
}

void WriteErrorMap(const std::string& path, const ImageF& error_deg, const Mask& mask,
                   double max_deg, const std::string& unit) {
  const int w = error_deg.width, h = error_deg.height;
  const double font = std::max(0.35, h / 900.0);
  // The labels first, so the bar is as wide as they need and none is cut off.
  std::vector<std::string> labels;
  int label_width = 0, baseline = 0;
  for (int tick = 0; tick <= 4; ++tick) {
    char label[32];
    std::snprintf(label, sizeof label, "%.3g", max_deg * tick / 4);
    labels.push_back(label);
    label_width = std::max(
        label_width, cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, font, 1, &baseline).width);
  }
  const int ramp_width = std::max(12, w / 32);
  const int bar = 10 + ramp_width + 4 + label_width + 8;
  cv::Mat gray(h, w, CV_8UC1, cv::Scalar(0));
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) {
      const double e = error_deg.pixels[static_cast<std::size_t>(row) * w + col];
      gray.at<unsigned char>(row, col) =
          static_cast<unsigned char>(std::clamp(e / max_deg, 0.0, 1.0) * 255 + 0.5);
    }
  cv::Mat colored;
  cv::applyColorMap(gray, colored, cv::COLORMAP_JET);
  cv::Mat canvas(h, w + bar, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col)
      canvas.at<cv::Vec3b>(row, col) =
          mask.at(col, row) ? colored.at<cv::Vec3b>(row, col) : cv::Vec3b(0, 0, 0);
  // Scale bar: top = max_deg, bottom = 0, labels to its right.
  const int top = 20, bottom = h - 12, x0 = w + 10, x1 = w + 10 + ramp_width;
  cv::Mat ramp(std::max(bottom - top, 1), 1, CV_8UC1);
  for (int i = 0; i < ramp.rows; ++i)
    ramp.at<unsigned char>(i, 0) = 255 - 255 * i / std::max(ramp.rows - 1, 1);
  cv::Mat ramp_colored;
  cv::applyColorMap(ramp, ramp_colored, cv::COLORMAP_JET);
  for (int i = 0; i < ramp.rows; ++i)
    cv::line(canvas, {x0, top + i}, {x1, top + i}, ramp_colored.at<cv::Vec3b>(i, 0));
  for (int tick = 0; tick <= 4; ++tick) {
    const int y = bottom - (bottom - top) * tick / 4;
    cv::putText(canvas, labels[tick], {x1 + 4, y + 4}, cv::FONT_HERSHEY_SIMPLEX, font,
                cv::Scalar(0, 0, 0));
  }
  cv::putText(canvas, unit, {x0, top - 6}, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(0, 0, 0));
  ImageF image(w + bar, h, 3);
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w + bar; ++col) {
      const cv::Vec3b bgr = canvas.at<cv::Vec3b>(row, col);
      for (int c = 0; c < 3; ++c) image.at(col, row)[c] = bgr[2 - c] / 255.0f;  // BGR → RGB
    }
  WriteImage(path, image, {8, Encoding::kLinear});
}

void WriteAlbedoPicture(const std::string& path, const ImageF& albedo, const Mask& mask) {
  const float scale = render::AlbedoDisplayScale(albedo);
  ImageF picture(albedo.width, albedo.height, 3);
  for (std::size_t p = 0; p < mask.inside.size(); ++p) {
    if (!mask.inside[p]) continue;
    for (int c = 0; c < 3; ++c) {
      picture.pixels[3 * p + c] =
          scale * albedo.pixels[p * albedo.channels + std::min(c, albedo.channels - 1)];
    }
  }
  WriteImage(path, picture, {8, Encoding::kSrgb});
}

ImageF LabelTiles(const ImageF& sheet, int tile_width, int tile_height, int label_height,
                  const std::vector<std::string>& labels) {
  const int columns = std::max(1, sheet.width / tile_width);
  const int rows = (static_cast<int>(labels.size()) + columns - 1) / columns;
  ImageF out(sheet.width, sheet.height + rows * label_height, 3);
  cv::Mat canvas(out.height, out.width, CV_8UC3, cv::Scalar(64, 64, 64));
  for (int row = 0; row < rows; ++row)
    for (int y = 0; y < tile_height && row * tile_height + y < sheet.height; ++y)
      for (int x = 0; x < sheet.width; ++x) {
        const float* v = sheet.at(x, row * tile_height + y);
        cv::Vec3b& c = canvas.at<cv::Vec3b>(row * (tile_height + label_height) + y, x);
        for (int k = 0; k < 3; ++k)
          c[2 - k] =
              static_cast<unsigned char>(std::clamp(LinearToSrgb(v[k]), 0.0f, 1.0f) * 255 + 0.5f);
      }
  const double font = std::max(0.35, label_height / 50.0);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const int col = static_cast<int>(i) % columns, row = static_cast<int>(i) / columns;
    int baseline = 0;
    double fitted = font;  // narrowed until the label fits its tile
    cv::Size size = cv::getTextSize(labels[i], cv::FONT_HERSHEY_SIMPLEX, fitted, 1, &baseline);
    if (size.width > tile_width - 8) {
      fitted *= (tile_width - 8.0) / size.width;
      size = cv::getTextSize(labels[i], cv::FONT_HERSHEY_SIMPLEX, fitted, 1, &baseline);
    }
    const int x = col * tile_width + std::max(0, (tile_width - size.width) / 2);
    const int y =
        row * (tile_height + label_height) + tile_height + (label_height + size.height) / 2;
    cv::putText(canvas, labels[i], {x, y}, cv::FONT_HERSHEY_SIMPLEX, fitted,
                cv::Scalar(235, 235, 235), 1, cv::LINE_AA);
  }
  for (int row = 0; row < out.height; ++row)
    for (int col = 0; col < out.width; ++col) {
      const cv::Vec3b bgr = canvas.at<cv::Vec3b>(row, col);
      for (int k = 0; k < 3; ++k) out.at(col, row)[k] = SrgbToLinear(bgr[2 - k] / 255.0f);
    }
  return out;
}

}  // namespace iphong::io
