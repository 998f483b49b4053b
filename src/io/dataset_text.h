// The text files of a dataset, parsed from memory: filenames.txt, light_directions.txt,
// light_intensities.txt, normal.txt and material.json. Kept apart from the file reading so the
// fuzz target (tests/fuzz) drives exactly what LoadDataset runs. Every error is a
// std::runtime_error "SOURCE[:LINE]: what is wrong (what is expected)". Lines may end in "\r\n",
// a file may start with a UTF-8 byte-order mark, and a line starting with '#' is a comment.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/types.h"
#include "reflectance/material.h"

namespace iphong::io {

// Coefficients from material.json. kd is optional: absent means an unknown per-pixel albedo.
struct DatasetMaterial {
  reflectance::Lobe model = reflectance::Lobe::kPhong;
  Vec3d ambient = Vec3d::Zero();
  reflectance::Material material;
  bool kd_known = false;
};

// One image name per non-blank line, trimmed; at least one, at most `max_images`.
std::vector<std::string> ParseFilenames(const std::string& text, const std::string& source,
                                        std::size_t max_images = 100000);

// `expected` lines of three finite numbers (separated by spaces, tabs or commas); a count that
// differs is reported against `count_source`, where the expected count came from.
// `lines` (optional) receives each triple's line number in the file.
std::vector<Vec3d> ParseTriples(const std::string& text, const std::string& source,
                                std::size_t expected,
                                const std::string& count_source = "filenames.txt",
                                std::vector<int>* lines = nullptr);

// `expected` lines of one finite number each (light_anisotropy.txt), with their line numbers.
std::vector<double> ParseScalars(const std::string& text, const std::string& source,
                                 std::size_t expected,
                                 const std::string& count_source = "filenames.txt",
                                 std::vector<int>* lines = nullptr);

// camera.json (SPEC.md "Near lights"): {"fx": …, "fy": …, "cx": …, "cy": …} in pixels, (cx, cy)
// in OpenCV's convention (from the top-left, rows down, pixel centres at integers), or iphong's
// {"pixel_size": …} (mm per pixel) for an orthographic camera centred on the image. Returned in
// iphong's pixel convention (centres at col + 0.5, row + 0.5: cx + 0.5). Other keys are left
// alone (other tools write "width", "distortion" …) and named in `ignored`, JSON-quoted (a key
// may hold any character, a line break among them).
struct CameraIntrinsics {
  bool perspective = true;
  double fx = 0, fy = 0, cx = 0, cy = 0;  // iphong's convention
  double pixel_size = 0;                  // orthographic, mm per pixel
};
CameraIntrinsics ParseCameraJson(const std::string& text, const std::string& source,
                                 std::vector<std::string>* ignored = nullptr);
std::string FormatCameraJson(const CameraIntrinsics& camera);

// What ParseTriples and ParseLightFile read back: "x y z" per line (%.9g), as in
// light_directions.txt, light_intensities.txt and light_positions.txt; and an RTI .lp, the
// count and then "name lx ly lz" per image (the same number of names and directions).
std::string FormatTriples(const std::vector<Vec3d>& rows);
std::string FormatLp(const std::vector<std::string>& names, const std::vector<Vec3d>& directions);

// A light file in any of the formats capture tools write, told apart by extension and content:
//   "directions"          DiLiGenT's light_directions.txt: one "lx ly lz" per line;
//   "count + directions"  UW/CSE455 lights.txt: a line with the count, then the directions;
//   "RTI .lp"             RTIBuilder, Relight, RTIViewer: a count line, then "filename lx ly lz"
//                         (the name may hold spaces; the last three fields are the direction);
//   "AliceVision JSON"    {"lights": [{"direction": [x, y, z], "intensity": [r, g, b]}, ...]} in
//                         AliceVision's camera frame (x right, y down, z away from the camera),
//                         turned into iphong's (x right, y up, z toward the viewer).
// All but the JSON share iphong's frame. Directions are normalized as ParseLightDirections does.
struct LightFile {
  std::string format;
  std::vector<Vec3d> directions;
  std::vector<std::string> image_names;  // RTI .lp: the image of each light, as written
  std::vector<Vec3d> intensities;        // AliceVision JSON: RGB per light; empty otherwise
};
// `expected` = 0 takes any count (the images are then matched to the lights by the caller).
LightFile ParseLightFile(const std::string& text, const std::string& source, std::size_t expected,
                         std::vector<std::string>* warnings, std::size_t max_lights = 100000);

// Light directions: non-zero, normalized (lengths off 1 by more than 1e-3 are reported in
// `warnings`). Intensities: each channel in [1e-30, 1e30] (solve::LightIntensityInRange).
std::vector<Vec3d> ParseLightDirections(const std::string& text, const std::string& source,
                                        std::size_t expected, std::vector<std::string>* warnings);
std::vector<Vec3d> ParseLightIntensities(const std::string& text, const std::string& source,
                                         std::size_t expected);

// width × height lines "nx ny nz", row-major from the top row.
ImageF ParseNormalText(const std::string& text, const std::string& source, int width, int height);

DatasetMaterial ParseMaterialJson(const std::string& text, const std::string& source);

}  // namespace iphong::io
