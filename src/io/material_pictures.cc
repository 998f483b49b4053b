#include "io/material_pictures.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "io/image_io.h"
#include "io/visualize.h"

namespace iphong::io {

namespace {

ImageF FromCanvas(const cv::Mat& canvas) {
  ImageF image(canvas.cols, canvas.rows, 3);
  for (int row = 0; row < canvas.rows; ++row)
    for (int col = 0; col < canvas.cols; ++col) {
      const cv::Vec3b bgr = canvas.at<cv::Vec3b>(row, col);
      for (int c = 0; c < 3; ++c) image.at(col, row)[c] = bgr[2 - c] / 255.0f;
    }
  return image;
}

// A tick step of 1, 2 or 5 × 10^k giving about five ticks over `range`.
double TickStep(double range) {
  const double raw = range / 5, decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (double s : {1.0, 2.0, 5.0}) {
    if (s * decade >= raw) return s * decade;
  }
  return 10 * decade;
}

}  // namespace

void WriteLobePlot(const std::string& path, const std::vector<material::LobeBin>& bins,
                   reflectance::Lobe lobe, double shininess, const std::string& title) {
  constexpr int kWidth = 720, kHeight = 460, kLeft = 70, kRight = 20, kTop = 40, kBottom = 60;
  cv::Mat canvas(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  double x_max = 10, y_min = 0, y_max = 1.1;
  for (const material::LobeBin& b : bins) {
    x_max = std::max(x_max, b.angle_deg + 0.5);
    y_min = std::min(y_min, b.mean - 2 * b.standard_error);
    y_max = std::max(y_max, b.mean + 2 * b.standard_error);
  }
  y_max = std::min(y_max, 3.0);  // a stray bin must not flatten the lobe
  y_min = std::max(y_min, -1.0);
  const int plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;
  auto px = [&](double x) { return kLeft + static_cast<int>(std::lround(x / x_max * plot_w)); };
  auto py = [&](double y) {
    return kTop + static_cast<int>(std::lround((y_max - y) / (y_max - y_min) * plot_h));
  };
  const cv::Scalar black(0, 0, 0), grey(200, 200, 200), blue(180, 90, 20), red(40, 40, 220);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  const double x_step = TickStep(x_max), y_step = TickStep(y_max - y_min);
  for (double x = 0; x <= x_max + 1e-9; x += x_step) {
    cv::line(canvas, {px(x), kTop}, {px(x), kTop + plot_h}, grey);
    char label[16];
    std::snprintf(label, sizeof label, "%g", x);
    cv::putText(canvas, label, {px(x) - 8, kTop + plot_h + 18}, font, 0.45, black, 1, cv::LINE_AA);
  }
  for (double y = std::ceil(y_min / y_step) * y_step; y <= y_max + 1e-9; y += y_step) {
    cv::line(canvas, {kLeft, py(y)}, {kLeft + plot_w, py(y)}, grey);
    char label[16];
    std::snprintf(label, sizeof label, "%.2g", std::abs(y) < 1e-12 ? 0.0 : y);
    cv::putText(canvas, label, {8, py(y) + 5}, font, 0.45, black, 1, cv::LINE_AA);
  }
  cv::rectangle(canvas, {kLeft, kTop}, {kLeft + plot_w, kTop + plot_h}, black);
  // The fitted lobe: cos(angle)^n.
  std::vector<cv::Point> curve;
  for (int i = 0; i <= 400; ++i) {
    const double x = x_max * i / 400;
    curve.emplace_back(px(x), py(std::pow(std::cos(x * M_PI / 180), shininess)));
  }
  cv::polylines(canvas, curve, false, red, 2, cv::LINE_AA);
  for (const material::LobeBin& b : bins) {
    const int x = px(b.angle_deg);
    cv::line(canvas, {x, py(std::min(y_max, b.mean + 2 * b.standard_error))},
             {x, py(std::max(y_min, b.mean - 2 * b.standard_error))}, blue, 1, cv::LINE_AA);
    if (b.mean <= y_max && b.mean >= y_min) {
      cv::circle(canvas, {x, py(b.mean)}, 4, blue, cv::FILLED, cv::LINE_AA);
    }
  }
  const std::string x_label = lobe == reflectance::Lobe::kBlinnPhong
                                  ? "angle between N and H (deg)"
                                  : "angle between R and V (deg)";
  cv::putText(canvas, x_label, {kLeft + plot_w / 2 - 110, kHeight - 18}, font, 0.5, black, 1,
              cv::LINE_AA);
  cv::putText(canvas, title, {kLeft, 25}, font, 0.5, black, 1, cv::LINE_AA);
  char legend[64];
  std::snprintf(legend, sizeof legend, "fitted cos^n, n = %.1f", shininess);
  cv::putText(canvas, legend, {kLeft + plot_w - 230, kTop + 22}, font, 0.5, red, 1, cv::LINE_AA);
  cv::putText(canvas, "data, +-2 s.e.", {kLeft + plot_w - 230, kTop + 44}, font, 0.5, blue, 1,
              cv::LINE_AA);
  WriteImage(path, FromCanvas(canvas), {8, Encoding::kLinear});
}

void WriteComparisonPicture(const std::string& path, const std::vector<ImageF>& observed,
                            const std::vector<ImageF>& predicted,
                            const std::vector<std::string>& light_labels) {
  // The tiles show the object: the box around every non-zero pixel, 4 px around it.
  const int full_w = observed.at(0).width, full_h = observed.at(0).height;
  int x0 = full_w, y0 = full_h, x1 = -1, y1 = -1;
  for (const ImageF& image : observed)
    for (int y = 0; y < full_h; ++y)
      for (int x = 0; x < full_w; ++x) {
        const float* v = image.at(x, y);
        if (v[0] > 0 || v[1] > 0 || v[2] > 0) {
          x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
      }
  if (x1 < 0) x0 = 0, y0 = 0, x1 = full_w - 1, y1 = full_h - 1;
  x0 = std::max(0, x0 - 4), y0 = std::max(0, y0 - 4);
  x1 = std::min(full_w - 1, x1 + 4), y1 = std::min(full_h - 1, y1 + 4);
  const int w = x1 - x0 + 1, h = y1 - y0 + 1;
  // One exposure for every tile: the observed 99th percentile (non-zero values) at 0.9.
  std::vector<float> values;
  for (const ImageF& image : observed)
    for (float v : image.pixels)
      if (v > 0) values.push_back(v);
  float top = 1;
  if (!values.empty()) {
    const std::size_t k = static_cast<std::size_t>(0.99 * (values.size() - 1));
    std::nth_element(values.begin(), values.begin() + k, values.end());
    top = std::max(values[k], 1e-6f);
  }
  const float exposure = 0.9f / top;
  const double shrink = std::min(1.0, 320.0 / std::max(w, h));
  const int tw = std::max(1, static_cast<int>(w * shrink)),
            th = std::max(1, static_cast<int>(h * shrink));
  const int rows = static_cast<int>(observed.size());
  ImageF sheet(3 * tw, rows * th, 3);
  std::vector<std::string> labels;
  for (int r = 0; r < rows; ++r) {
    for (int col = 0; col < 3; ++col) {
      cv::Mat tile(h, w, CV_32FC3);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          for (int c = 0; c < 3; ++c) {
            const float o = observed[r].at(x0 + x, y0 + y)[c];
            const float p = predicted[r].at(x0 + x, y0 + y)[c];
            const float v = col == 0 ? o : col == 1 ? p : 4 * std::abs(o - p);
            tile.at<cv::Vec3f>(y, x)[c] = v * exposure;
          }
      cv::Mat small;
      cv::resize(tile, small, {tw, th}, 0, 0, cv::INTER_AREA);
      for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x)
          for (int c = 0; c < 3; ++c)
            sheet.at(col * tw + x, r * th + y)[c] = small.at<cv::Vec3f>(y, x)[c];
    }
    labels.push_back(light_labels[r] + ": observed");
    labels.push_back("predicted");
    labels.push_back("|difference| x 4");
  }
  WriteImage(path, LabelTiles(sheet, tw, th, 24, labels), {8, Encoding::kSrgb});
}

}  // namespace iphong::io
