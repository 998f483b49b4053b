// Finding a capture's files in a folder, whichever tool wrote it. Each layout has its reader; all
// of them produce one CaptureFiles, from which LoadDataset (io/dataset.h) reads the images.
//
// Layouts, tried in this order:
//   DiLiGenT  filenames.txt names the images; light_directions.txt, light_intensities.txt,
//             mask.png, Normal_gt.mat (or normal.txt), material.json beside it.
//   RTI       a .lp file (RTIBuilder, Relight, RTIViewer) names the images and their lights.
//   listed    a text file naming the images, one per line (a count line first allowed, the mask
//             among them taken as the mask): `images` when given, else <folder>.txt or
//             images.txt here, else <folder>.txt one folder up (UW's archive).
//   folder    every image file in the folder, in natural order ("cat.2" before "cat.10"; a
//             plain `ls` puts cat.10 first and pairs every image with the wrong light).
// The light file, unless named: light_directions.txt, lights.txt, lights.json or the one .lp in
// the folder; the one .lp in its subfolders (RTIBuilder's assembly-files/); then lights.txt,
// light_directions.txt or the one .lp in the parent folder (UW keeps one lights.txt beside its
// objects). Any format of ParseLightFile (io/dataset_text.h). A DiLiGenT folder with
// light_positions.txt is a near-light capture (io/near_capture.h), light_directions.txt then
// optional. Intensities: light_intensities.txt,
// else the light file's (AliceVision JSON), else all 1. The mask, unless named: mask.png, then
// mask.* , <name>.mask.*, <name>_mask.* (an image file whose name without extension is "mask" or
// ends in ".mask", "_mask" or "-mask"); none = the whole image. Ground truth: Normal_gt.mat or
// normal.txt.
#pragma once

#include <string>
#include <vector>

#include "core/image_ops.h"
#include "core/types.h"
#include "io/image_io.h"
#include "io/near_capture.h"

namespace iphong::io {

// CaptureOptions::intensities naming no file: every light's intensity 1, whatever intensity file
// the capture holds (`--intensities none`).
inline constexpr const char* kNoIntensities = "none";

struct CaptureOptions {
  std::string lights;       // a light file; "" = find one
  std::string intensities;  // "r g b" per light; "" = find one; kNoIntensities = all 1
  std::string mask;         // a mask picture; "" = find one
  // A list of the photos in light order (io/image_list.h); "" = the layout's own.
  std::string images;
  std::string encoding = "auto";  // "auto" (what the files say, else linear), "linear", "srgb"
  PixelRect crop;                 // in the files' pixels, applied first; width 0 = none
  int downscale = 1;              // then area averaging by this factor
  // False for captures whose lights are what is sought (calibrate-lights): no light file is
  // looked for or read, light_directions stays empty and the intensities are all 1.
  bool lights_needed = true;

  std::string Check() const;  // "" or what is wrong
};

struct CaptureFiles {
  std::string directory;
  std::string layout;              // "DiLiGenT", "RTI .lp", "listed", "folder"
  std::vector<std::string> names;  // each image as listed or found
  std::vector<std::string> paths;  // each image's path
  std::string order;               // how the order was decided
  std::string lights_path, lights_format;
  std::vector<Vec3d> light_directions;   // unit, camera frame (SPEC.md)
  std::vector<Vec3d> light_intensities;  // RGB
  std::string intensities_source;
  bool intensities_from_file = false;  // a file gave them (not all 1, not unread)
  std::string mask_path;               // "" = the whole image
  std::string ground_truth_path;       // "" = none
  std::string material_path;           // "" = none
  std::string render_json;             // iphong's own render.json, which states the encoding
  // Near lights (io/near_capture.h): light_positions.txt and camera.json; light_directions are
  // then the file's or, without one, those toward the positions from the object.
  NearLightFiles near;
  std::vector<std::string> warnings;
  // Files beside the photos that look like a dataset's or iphong's companions (an albedo or
  // normal picture, *.normals.dat) and were not read as photos.
  std::vector<std::string> skipped;
};

// Throws std::runtime_error naming the file (and line) that is missing or wrong: no images, no
// light file, counts that differ (with the names found), an image a .lp names that is not there.
CaptureFiles FindCapture(const std::string& directory, const CaptureOptions& options);

// The encoding the images are read with, and why: --encoding when given; iphong's render.json;
// linear for float files; what the first image states (StoredEncoding); linear otherwise — the
// raw data of a camera or a benchmark (DiLiGenT's 8-bit crops, UW's TGA files) is linear more
// often than not, and on UW's matte gray sphere linear gives 5.1° where sRGB gives 16.4°.
struct EncodingChoice {
  Encoding encoding = Encoding::kLinear;
  std::string reason;
  // Linear by default, for integer files that state nothing: what the data say is worth asking
  // (solve/reading_check.h).
  bool assumed = false;
};
EncodingChoice ChooseEncoding(const CaptureFiles& files, const CaptureOptions& options,
                              const StoredEncoding& first_image);

// "a" before "b", "img2" before "img10" (digit runs compare as numbers), case folded.
bool NaturalLess(const std::string& a, const std::string& b);

// True for the extensions of the image formats iphong reads from capture folders.
bool HasImageExtension(const std::string& name);

// 0: "mask.*"; 1: "<x>.mask.*", "<x>_mask.*", "<x>-mask.*"; -1: not a mask's name (an image
// file's name only).
int MaskNameRank(const std::string& name);

// Files of a capture folder that are not photographs: masks, ground truth and what iphong and
// the datasets' tools write beside the photos (normals, depth, albedo, ... alone or as the last
// part of the name: UW's buddha.albedo.tga).
bool IsCompanionImage(const std::string& name);

}  // namespace iphong::io
