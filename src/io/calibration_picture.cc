#include "io/calibration_picture.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <set>

#include "io/image_io.h"

namespace iphong::io {
namespace {

constexpr int kPanel = 512;

cv::Scalar Colour(int i) {  // BGR, distinct for neighbours
  static const cv::Scalar kColours[] = {{80, 200, 255},  {255, 160, 80}, {120, 255, 120},
                                        {255, 120, 255}, {80, 255, 255}, {200, 200, 255}};
  return kColours[i % 6];
}

void Label(cv::Mat& canvas, const std::string& text, cv::Point at, const cv::Scalar& colour) {
  cv::putText(canvas, text, at + cv::Point(5, -5), cv::FONT_HERSHEY_SIMPLEX, 0.4, colour, 1,
              cv::LINE_AA);
}

}  // namespace

std::vector<std::string> ImageLabels(const std::vector<std::string>& file_names) {
  std::vector<std::string> labels;
  std::set<std::string> seen;
  for (const std::string& name : file_names) {
    const std::string stem = std::filesystem::path(name).stem().string();
    std::size_t end = stem.size();
    while (end > 0 && !std::isdigit(static_cast<unsigned char>(stem[end - 1]))) --end;
    std::size_t begin = end;
    while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
    if (begin == end) break;
    while (begin + 1 < end && stem[begin] == '0') ++begin;
    labels.push_back(stem.substr(begin, end - begin));
    if (!seen.insert(labels.back()).second) {
      labels.clear();
      break;
    }
  }
  if (labels.size() == file_names.size()) return labels;
  labels.clear();
  for (std::size_t j = 0; j < file_names.size(); ++j) labels.push_back(std::to_string(j + 1));
  return labels;
}

ImageF CalibrationPicture(const CalibrationPictureInput& in) {
  auto label = [&](std::size_t j) {
    return j < in.labels.size() ? in.labels[j] : std::to_string(j + 1);
  };
  cv::Mat canvas(kPanel, 2 * kPanel, CV_8UC3, cv::Scalar(30, 30, 30));
  // Left: the region around the spheres, scaled to the panel.
  const ImageF& bg = *in.background;
  double x0 = 0, y0 = 0, x1 = bg.width, y1 = bg.height;
  if (!in.circles.empty()) {
    x0 = y0 = 1e300;
    x1 = y1 = -1e300;
    for (const Vec3d& c : in.circles) {
      x0 = std::min(x0, c.x() - 1.15 * c.z());
      x1 = std::max(x1, c.x() + 1.15 * c.z());
      y0 = std::min(y0, c.y() - 1.15 * c.z());
      y1 = std::max(y1, c.y() + 1.15 * c.z());
    }
  }
  const double scale = kPanel / std::max(x1 - x0, y1 - y0);
  // Tone: the 99.5th percentile of the shown pixels maps to white, through a square root, so
  // the dim sphere shows beside its highlights.
  std::vector<float> shown;
  for (int r = std::max(0, int(y0)); r < std::min(bg.height, int(y1)); r += 2)
    for (int c = std::max(0, int(x0)); c < std::min(bg.width, int(x1)); c += 2)
      shown.push_back(*std::max_element(bg.at(c, r), bg.at(c, r) + bg.channels));
  float white = 1;
  if (!shown.empty()) {
    std::nth_element(shown.begin(), shown.begin() + shown.size() * 995 / 1000, shown.end());
    white = std::max(shown[shown.size() * 995 / 1000], 1e-6f);
  }
  for (int y = 0; y < kPanel; ++y) {
    for (int x = 0; x < kPanel; ++x) {
      const int c = int(std::floor(x0 + (x + 0.5) / scale)),
                r = int(std::floor(y0 + (y + 0.5) / scale));
      if (c < 0 || r < 0 || c >= bg.width || r >= bg.height) continue;
      const float* v = bg.at(c, r);
      cv::Vec3b& out = canvas.at<cv::Vec3b>(y, x);
      for (int k = 0; k < 3; ++k) {
        const float value = v[std::min(k, bg.channels - 1)] / white;
        out[2 - k] = cv::saturate_cast<unsigned char>(255 * std::sqrt(std::clamp(value, 0.f, 1.f)));
      }
    }
  }
  auto to_left = [&](double x, double y) {
    return cv::Point(int(std::lround((x - x0) * scale)), int(std::lround((y - y0) * scale)));
  };
  for (const Vec3d& c : in.circles) {
    cv::circle(canvas, to_left(c.x(), c.y()), int(std::lround(c.z() * scale)),
               cv::Scalar(255, 200, 120), 1, cv::LINE_AA);
  }
  for (std::size_t j = 0; j < in.marks.size(); ++j) {
    for (const Vec2d& m : in.marks[j]) {
      const cv::Point p = to_left(m.x(), m.y());
      cv::circle(canvas, p, 4, Colour(int(j)), 1, cv::LINE_AA);
      Label(canvas, label(j), p, Colour(int(j)));
    }
  }

  // Right: the hemisphere as the camera sees it (orthographic: x, y of each direction).
  const cv::Point centre(kPanel + kPanel / 2, kPanel / 2);
  const double radius = kPanel / 2 - 24;
  cv::circle(canvas, centre, int(radius), cv::Scalar(160, 160, 160), 1, cv::LINE_AA);
  for (double elevation : {30.0, 60.0}) {
    cv::circle(canvas, centre, int(radius * std::cos(elevation * M_PI / 180)),
               cv::Scalar(90, 90, 90), 1, cv::LINE_AA);
  }
  cv::line(canvas, centre - cv::Point(int(radius), 0), centre + cv::Point(int(radius), 0),
           cv::Scalar(90, 90, 90));
  cv::line(canvas, centre - cv::Point(0, int(radius)), centre + cv::Point(0, int(radius)),
           cv::Scalar(90, 90, 90));
  cv::putText(canvas, "+x", centre + cv::Point(int(radius) + 2, 14), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(160, 160, 160), 1, cv::LINE_AA);
  cv::putText(canvas, "+y", centre + cv::Point(4, -int(radius) - 6), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(160, 160, 160), 1, cv::LINE_AA);
  cv::putText(canvas, "lights seen from the camera; rings at 30 and 60 deg elevation",
              cv::Point(kPanel + 8, kPanel - 8), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(160, 160, 160), 1, cv::LINE_AA);
  for (std::size_t j = 0; j < in.light_dir_cam.size(); ++j) {
    const Vec3d& l = in.light_dir_cam[j];
    if (l.norm() == 0) continue;
    const cv::Point p =
        centre + cv::Point(int(std::lround(radius * l.x())), int(std::lround(-radius * l.y())));
    const cv::Scalar colour = l.z() < 0 ? cv::Scalar(60, 60, 255) : Colour(int(j));
    cv::circle(canvas, p, 3, colour, cv::FILLED, cv::LINE_AA);
    Label(canvas, label(j), p, colour);
  }

  ImageF out(canvas.cols, canvas.rows, 3);
  for (int y = 0; y < canvas.rows; ++y) {
    for (int x = 0; x < canvas.cols; ++x) {
      const cv::Vec3b& v = canvas.at<cv::Vec3b>(y, x);
      float* o = out.at(x, y);
      for (int k = 0; k < 3; ++k) o[k] = SrgbToLinear(v[2 - k] / 255.0f);
    }
  }
  return out;
}

}  // namespace iphong::io
