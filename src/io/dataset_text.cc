#include "io/dataset_text.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <stdexcept>

#include "core/errors.h"
#include "io/json_reader.h"
#include "io/scene_file.h"
#include "solve/photometric_data.h"

namespace iphong::io {
namespace {

// Non-blank lines with their numbers; "\r\n" endings accepted. A line whose first non-blank
// character is '#' is a comment (numpy.savetxt writes its header so, and MATLAB and spreadsheet
// exports are often annotated the same way).
std::vector<std::pair<int, std::string>> Lines(const std::string& text) {
  std::vector<std::pair<int, std::string>> lines;
  // Editors on Windows start UTF-8 files with a byte-order mark; it is not part of line 1.
  std::size_t start = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  for (int number = 1; start <= text.size(); ++number) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::size_t first = line.find_first_not_of(" \t");
    if (first != std::string::npos && line[first] != '#') lines.emplace_back(number, line);
    start = end + 1;
  }
  return lines;
}

// A line shown in a message: printable and short.
std::string Shown(const std::string& line) {
  std::string out;
  for (char c : line.substr(0, 60)) out += (c >= 32 && c < 127) ? c : '?';
  return line.size() > 60 ? out + "..." : out;
}

// Three numbers and nothing else; strtod, unlike operator>>, reads "nan" and "inf", so they get
// their own message instead of "expected 3 numbers".
// `grey`: one number stands for the same value in R, G and B (a grey light's intensity).
Vec3d Triple(const std::string& line, const std::string& source, int number, bool grey = false) {
  if (line.find('\0') != std::string::npos) FailInput(source, "not a text file", number);
  Vec3d v;
  const char* p = line.c_str();
  int count = 0;
  for (; count < 4; ++count) {
    if (count > 0) p += std::strspn(p, " \t,");  // "1, 2, 3" as spreadsheets export it
    char* end = nullptr;
    const double value = std::strtod(p, &end);
    if (end == p) break;
    if (count < 3) v[count] = value;
    p = end;
  }
  if (grey && count == 1) v = Vec3d::Constant(v[0]);
  if ((count != 3 && !(grey && count == 1)) ||
      std::string(p).find_first_not_of(" \t,") != std::string::npos) {
    FailInput(
        source,
        std::string(grey ? "expected 3 numbers (or 1 for a grey light)" : "expected 3 numbers") +
            ", got '" + Shown(line) + "'",
        number);
  }
  if (!v.allFinite()) FailInput(source, "not a finite number: '" + Shown(line) + "'", number);
  return v;
}

}  // namespace

std::vector<std::string> ParseFilenames(const std::string& text, const std::string& source,
                                        std::size_t max_images) {
  std::vector<std::string> names;
  for (const auto& [number, line] : Lines(text)) {
    const auto begin = line.find_first_not_of(" \t"), end = line.find_last_not_of(" \t");
    std::string name = line.substr(begin, end - begin + 1);
    for (unsigned char c : name) {
      if (c < 32) FailInput(source, "an image name with control characters", number);
    }
    if (names.size() == max_images) {
      FailInput(source, "lists more than " + std::to_string(max_images) + " images", number);
    }
    names.push_back(std::move(name));
  }
  if (names.empty()) FailInput(source, "lists no images (one file name per line expected)");
  return names;
}

std::string FormatTriples(const std::vector<Vec3d>& rows) {
  std::string text;
  char line[128];
  for (const Vec3d& v : rows) {
    std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", v[0], v[1], v[2]);
    text += line;
  }
  return text;
}

std::string FormatLp(const std::vector<std::string>& names, const std::vector<Vec3d>& directions) {
  if (names.size() != directions.size()) {
    throw std::invalid_argument("FormatLp: " + std::to_string(names.size()) + " names, " +
                                std::to_string(directions.size()) + " directions");
  }
  std::string text = std::to_string(names.size()) + "\n";
  const std::string rows = FormatTriples(directions);
  std::size_t start = 0;
  for (const std::string& name : names) {
    const std::size_t end = rows.find('\n', start) + 1;
    text += name + " " + rows.substr(start, end - start);
    start = end;
  }
  return text;
}

namespace {

// One value per line, `expected` of them (the images counted in `count_source`): a line beyond
// them names itself, too few name the count. parse_one(line, number) reads one value.
template <typename T, typename ParseOne>
std::vector<T> ParseCounted(const std::string& text, const std::string& source,
                            std::size_t expected, const std::string& count_source,
                            std::vector<int>* lines, ParseOne parse_one) {
  std::vector<T> values;
  if (lines) lines->clear();
  for (const auto& [number, line] : Lines(text)) {
    if (values.size() == expected) {
      FailInput(
          source,
          "has more lines than the " + std::to_string(expected) + " images in " + count_source,
          number);
    }
    values.push_back(parse_one(line, number));
    if (lines) lines->push_back(number);
  }
  if (values.size() != expected) {
    FailInput(source, "has " + std::to_string(values.size()) + " lines for " +
                          std::to_string(expected) + " images in " + count_source);
  }
  return values;
}

}  // namespace

std::vector<Vec3d> ParseTriples(const std::string& text, const std::string& source,
                                std::size_t expected, const std::string& count_source,
                                std::vector<int>* lines) {
  return ParseCounted<Vec3d>(
      text, source, expected, count_source, lines,
      [&](const std::string& line, int number) { return Triple(line, source, number); });
}

std::vector<double> ParseScalars(const std::string& text, const std::string& source,
                                 std::size_t expected, const std::string& count_source,
                                 std::vector<int>* lines) {
  return ParseCounted<double>(
      text, source, expected, count_source, lines, [&](const std::string& line, int number) {
        if (line.find('\0') != std::string::npos) FailInput(source, "not a text file", number);
        const char* p = line.c_str();
        char* end = nullptr;
        const double value = std::strtod(p, &end);
        if (end == p || std::string(end).find_first_not_of(" \t,") != std::string::npos) {
          FailInput(source, "expected one number, got '" + Shown(line) + "'", number);
        }
        if (!std::isfinite(value)) {
          FailInput(source, "not a finite number: '" + Shown(line) + "'", number);
        }
        return value;
      });
}

CameraIntrinsics ParseCameraJson(const std::string& text, const std::string& source,
                                 std::vector<std::string>* ignored) {
  const nlohmann::json document = JsonReader::Parse(text, source);
  const JsonReader j(document, source);
  if (!document.is_object())
    j.Fail("expected an object {\"fx\": ..., \"fy\": ..., \"cx\": ..., \"cy\": ...}");
  const std::set<std::string> known = {"fx", "fy", "cx", "cy", "pixel_size"};
  if (ignored) {
    for (const auto& item : document.items()) {
      if (!known.count(item.key())) ignored->push_back(nlohmann::json(item.key()).dump());
    }
  }
  CameraIntrinsics c;
  if (j.Has("pixel_size")) {
    for (const char* key : {"fx", "fy", "cx", "cy"}) {
      if (j.Has(key)) {
        j.Fail("gives both pixel_size (an orthographic camera) and " + std::string(key) +
               " (a perspective one)");
      }
    }
    c.perspective = false;
    c.pixel_size = j.Field("pixel_size").Number();
    if (!(c.pixel_size > 0) || !std::isfinite(c.pixel_size) || c.pixel_size > 1e6) {
      j.Field("pixel_size").Fail("expected a pixel size in mm > 0");
    }
    return c;
  }
  std::string missing;
  for (const char* key : {"fx", "fy", "cx", "cy"}) {
    if (!j.Has(key)) missing += std::string(missing.empty() ? "" : ", ") + key;
  }
  if (!missing.empty()) {
    j.Fail("needs the four intrinsics fx, fy, cx, cy in pixels (missing " + missing +
           "), or pixel_size in mm for an orthographic camera");
  }
  c.fx = j.Field("fx").Number();
  c.fy = j.Field("fy").Number();
  for (const char* key : {"fx", "fy"}) {
    const double f = j.Field(key).Number();
    if (!(f > 0) || !(f < 1e7)) j.Field(key).Fail("expected a focal length in pixels > 0");
  }
  const double cx = j.Field("cx").Number(), cy = j.Field("cy").Number();
  if (!(std::abs(cx) < 1e7) || !(std::abs(cy) < 1e7)) {
    j.Fail("expected a principal point cx, cy in pixels");
  }
  c.cx = cx + 0.5;
  c.cy = cy + 0.5;
  return c;
}

std::string FormatCameraJson(const CameraIntrinsics& c) {
  nlohmann::json j;
  if (c.perspective) {
    j = {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx - 0.5}, {"cy", c.cy - 0.5}};
  } else {
    j = {{"pixel_size", c.pixel_size}};
  }
  return j.dump(2) + "\n";
}

namespace {

// Unit directions (lengths off 1 by more than 1e-3 are reported), spanning three dimensions.
void NormalizeDirections(std::vector<Vec3d>& directions, const std::string& source,
                         std::vector<std::string>* warnings, int first_line) {
  // One warning for the file: the first line off, and how many (a file of unnormalized
  // directions said the same thing once per light).
  std::size_t off = 0;
  int first_off = 0;
  double first_length = 0;
  for (std::size_t i = 0; i < directions.size(); ++i) {
    Vec3d& d = directions[i];
    const int line = first_line + static_cast<int>(i);
    // Scaled first, so 1e308 components have a length instead of an infinite one.
    const double scale = d.cwiseAbs().maxCoeff();
    if (!(scale > 0)) FailInput(source, "zero light direction", line);
    const double norm = (d / scale).norm() * scale;
    // A denormal or near-zero vector has no direction worth normalizing: 1e-320 0 0 is a slip.
    if (norm < 1e-6) {
      char length[32];
      std::snprintf(length, sizeof length, "%.3g", norm);
      FailInput(source, std::string("light direction has length ") + length + ": not a direction",
                line);
    }
    if (std::abs(norm - 1) > 1e-3 && off++ == 0) first_off = line, first_length = norm;
    d = (d / scale).normalized();
  }
  if (off > 0 && warnings) {
    char length[32];
    std::snprintf(length, sizeof length, "%.6g", first_length);
    warnings->push_back(source + ":" + std::to_string(first_off) + ": light direction has length " +
                        length + "; normalized" +
                        (off > 1 ? " (as are " + std::to_string(off - 1) + " more of the " +
                                       std::to_string(directions.size()) + " directions)"
                                 : std::string()));
  }
  if (std::string m = solve::CheckLightSpan(directions); !m.empty()) FailInput(source, m);
  // A light behind the surface's plane as seen from the camera reaches only what faces away from
  // it: a few such lights are a rim setup, most of them a file in another frame (OpenCV's and
  // many renderers': y down, z into the scene), which gives normals turned inside out.
  const std::size_t behind = solve::LightsBehind(directions);
  if (warnings && solve::MostLightsBehind(directions)) {
    warnings->push_back(source + ": " + std::to_string(behind) + " of " +
                        std::to_string(directions.size()) +
                        " light directions point away from the camera (z < 0); iphong's frame "
                        "has x right, y up, z toward the camera: a file with y down and z into "
                        "the scene needs y and z negated");
  }
}

bool EndsWith(std::string text, const std::string& suffix) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The count a UW or RTI light file starts with: a line holding one non-negative integer only.
bool CountLine(const std::string& line, std::size_t* count) {
  const auto begin = line.find_first_not_of(" \t"), end = line.find_last_not_of(" \t");
  const std::string token = line.substr(begin, end - begin + 1);
  if (token.empty() || token.size() > 9 ||
      token.find_first_not_of("0123456789") != std::string::npos) {
    return false;
  }
  *count = std::stoul(token);
  return true;
}

LightFile ParseAliceVisionJson(const std::string& text, const std::string& source,
                               std::size_t max_lights) {
  const nlohmann::json document = JsonReader::Parse(text, source);
  const JsonReader root(document, source);
  const JsonReader lights = root.Field("lights");
  const std::size_t n = lights.Size();
  if (n > max_lights) lights.Fail("more than " + std::to_string(max_lights) + " lights");
  LightFile file;
  file.format = "AliceVision JSON";
  for (std::size_t i = 0; i < n; ++i) {
    const JsonReader light = lights.At(i);
    light.OnlyKeys({"lightId", "viewId", "type", "direction", "intensity"});
    const std::string type = light.String("type", "directional");
    if (type != "directional" && type != "directionnal" && type != "Directionnal") {
      light.Field("type").Fail("only directional lights are read (got " + type + ")");
    }
    const Vec3d d = light.Field("direction").Vector3();
    file.directions.push_back(Vec3d(d[0], -d[1], -d[2]));  // y down, z away → y up, z toward
    const Vec3d e = light.Rgb("intensity", Vec3d::Ones());
    if (!solve::LightIntensityInRange(e)) {
      light.Field("intensity").Fail("must be between 1e-30 and 1e30");
    }
    file.intensities.push_back(e);
  }
  if (file.directions.empty()) lights.Fail("no lights");
  return file;
}

}  // namespace

LightFile ParseLightFile(const std::string& text, const std::string& source, std::size_t expected,
                         std::vector<std::string>* warnings, std::size_t max_lights) {
  LightFile file;
  int first_line = 1;
  if (EndsWith(source, ".json")) {
    file = ParseAliceVisionJson(text, source, max_lights);
  } else {
    auto lines = Lines(text);
    if (lines.empty()) FailInput(source, "is empty (one light direction per line expected)");
    std::size_t count = 0;
    const bool counted = CountLine(lines.front().second, &count);
    if (counted) {
      if (lines.size() - 1 != count) {
        FailInput(source,
                  "says " + std::to_string(count) + " lights on its first line but lists " +
                      std::to_string(lines.size() - 1),
                  lines.front().first);
      }
      lines.erase(lines.begin());
    }
    if (lines.size() > max_lights) {
      FailInput(source, "lists more than " + std::to_string(max_lights) + " lights");
    }
    if (!lines.empty()) first_line = lines.front().first;
    // RTI: "name lx ly lz" — a first field that is not a number.
    const std::string& probe = lines.empty() ? std::string() : lines.front().second;
    // A first field that is not a whole number ("001.png" starts like one).
    char* end = nullptr;
    const char* start = probe.c_str() + probe.find_first_not_of(" \t");
    std::strtod(start, &end);
    const bool named =
        !probe.empty() && (end == start || (*end != '\0' && std::strchr(" \t,", *end) == nullptr));
    file.format = named ? "RTI .lp" : counted ? "count + directions" : "directions";
    for (const auto& [number, line] : lines) {
      if (line.find('\0') != std::string::npos) FailInput(source, "not a text file", number);
      if (!named) {
        file.directions.push_back(Triple(line, source, number));
        continue;
      }
      // The last three fields are the direction; everything before them is the file name.
      std::vector<std::size_t> starts;
      for (std::size_t at = line.find_first_not_of(" \t"); at != std::string::npos;
           at = line.find_first_not_of(" \t", line.find_first_of(" \t", at))) {
        starts.push_back(at);
      }
      if (starts.size() < 4) {
        FailInput(source, "expected 'filename lx ly lz', got '" + Shown(line) + "'", number);
      }
      std::string name = line.substr(0, starts[starts.size() - 3]);
      name.erase(name.find_last_not_of(" \t") + 1);
      for (unsigned char c : name) {
        if (c < 32) FailInput(source, "an image name with control characters", number);
      }
      file.image_names.push_back(name);
      file.directions.push_back(Triple(line.substr(starts[starts.size() - 3]), source, number));
    }
  }
  if (file.directions.empty()) FailInput(source, "lists no lights");
  if (expected > 0 && file.directions.size() != expected) {
    FailInput(source, "has " + std::to_string(file.directions.size()) + " lights for " +
                          std::to_string(expected) + " images");
  }
  NormalizeDirections(file.directions, source, warnings, first_line);
  return file;
}

std::vector<Vec3d> ParseLightDirections(const std::string& text, const std::string& source,
                                        std::size_t expected, std::vector<std::string>* warnings) {
  std::vector<Vec3d> directions = ParseTriples(text, source, expected);
  NormalizeDirections(directions, source, warnings, 1);
  return directions;
}

std::vector<Vec3d> ParseLightIntensities(const std::string& text, const std::string& source,
                                         std::size_t expected) {
  std::vector<Vec3d> intensities = ParseCounted<Vec3d>(
      text, source, expected, "filenames.txt", nullptr,
      [&](const std::string& line, int number) { return Triple(line, source, number, true); });
  for (std::size_t i = 0; i < intensities.size(); ++i) {
    if (!solve::LightIntensityInRange(intensities[i])) {
      FailInput(source, "light intensities must be between 1e-30 and 1e30",
                static_cast<int>(i + 1));
    }
  }
  return intensities;
}

ImageF ParseNormalText(const std::string& text, const std::string& source, int width, int height) {
  const auto lines = Lines(text);
  const std::size_t expected = static_cast<std::size_t>(width) * height;
  if (lines.size() != expected) {
    FailInput(source, "has " + std::to_string(lines.size()) + " lines, expected " +
                          std::to_string(expected) + " (width x height of the images)");
  }
  ImageF normals(width, height, 3);
  for (std::size_t p = 0; p < lines.size(); ++p) {
    const Vec3d n = Triple(lines[p].second, source, lines[p].first);
    for (int c = 0; c < 3; ++c) normals.pixels[3 * p + c] = static_cast<float>(n[c]);
  }
  return normals;
}

DatasetMaterial ParseMaterialJson(const std::string& text, const std::string& source) {
  const nlohmann::json document = JsonReader::Parse(text, source);
  const JsonReader j(document, source);
  j.OnlyKeys({"model", "ambient", "ka", "kd", "ks", "shininess", "comment"});
  DatasetMaterial m;
  try {
    m.model = reflectance::ParseLobe(j.String("model", "phong"));
  } catch (const std::invalid_argument& e) {
    j.Field("model").Fail(e.what());
  }
  m.ambient = j.Rgb("ambient", Vec3d::Ones());
  m.kd_known = j.Has("kd");
  reflectance::Material unknown;  // ka, ks 0, shininess 1; kd only a placeholder when absent
  unknown.kd = Vec3d::Ones();
  m.material = ReadMaterialCoefficients(j, unknown);
  if ((m.ambient.array() < 0).any()) j.Field("ambient").Fail("must be >= 0");
  return m;
}

}  // namespace iphong::io
