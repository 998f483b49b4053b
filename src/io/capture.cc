#include "io/capture.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>

#include "core/errors.h"
#include "io/dataset_text.h"
#include "io/files.h"
#include "io/image_list.h"
#include "io/json_reader.h"

namespace iphong::io {
namespace fs = std::filesystem;
namespace {

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// Present under that name: a FIFO or a folder named like a light file is then refused by its
// reader, not skipped as if absent.
// The regular files of a folder, in natural order. Hidden files (iphong's staging and manifest
// among them) are not part of a capture.
std::vector<std::string> FolderFiles(const fs::path& dir) {
  std::vector<std::string> names;
  std::error_code error;
  for (fs::directory_iterator it(dir, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (name.empty() || name[0] == '.') continue;
    std::error_code status_error;
    if (!it->is_regular_file(status_error)) continue;
    names.push_back(name);
    if (names.size() > 1000000)
      FailInput(dir, "holds more than a million files; not a capture folder");
  }
  if (error) FailInput(dir, "cannot list the folder: " + error.message());
  std::sort(names.begin(), names.end(), NaturalLess);
  return names;
}

// The folder itself, absolute and without a trailing separator: "uw/cat/" and "." have a name
// and a parent like any other folder.
fs::path Absolute(const fs::path& dir) {
  fs::path path = fs::absolute(dir).lexically_normal();
  if (!path.has_filename() && path.has_parent_path()) path = path.parent_path();
  return path;
}

std::string Stem(const std::string& name) {
  const std::size_t dot = name.rfind('.');
  return dot == std::string::npos ? name : name.substr(0, dot);
}

// The one file in `names` with extension `ext` (lower case, with the dot), or "".
std::string OnlyWithExtension(const std::vector<std::string>& names, const std::string& ext,
                              const fs::path& dir) {
  std::string found;
  for (const std::string& n : names) {
    if (Lower(fs::path(n).extension().string()) != ext) continue;
    if (!found.empty()) {
      FailInput(dir, "holds several " + ext + " files (" + found + ", " + n +
                         "); name the light file with --lights");
    }
    found = n;
  }
  return found;
}

fs::path FindLightFile(const fs::path& dir, const std::vector<std::string>& files) {
  for (const char* name : {"light_directions.txt", "lights.txt", "lights.json"})
    if (Exists(dir / name)) return dir / name;
  if (std::string lp = OnlyWithExtension(files, ".lp", dir); !lp.empty()) return dir / lp;
  // RTIBuilder keeps its .lp in a subfolder (assembly-files/) beside the images.
  // A subfolder that cannot be read (or is not the user's business) is passed over, not an error.
  // A .lp here that is not a regular file (a pipe, say) is still the light file the user meant:
  // the reader then names it and says what it is, instead of "found no .lp file" on the folder.
  std::vector<fs::path> nested;
  fs::path own;
  std::error_code list_error;
  for (fs::directory_iterator it(dir, list_error), end; !list_error && it != end;
       it.increment(list_error)) {
    if (it->path().filename().string()[0] == '.') continue;
    std::error_code status_error;
    if (!it->is_directory(status_error)) {
      if (Lower(it->path().extension().string()) == ".lp") own = it->path();
      continue;
    }
    std::error_code sub_error;
    for (fs::directory_iterator f(it->path(), sub_error), last; !sub_error && f != last;
         f.increment(sub_error)) {
      if (Lower(f->path().extension().string()) == ".lp") nested.push_back(f->path());
    }
  }
  if (!own.empty()) return dir / own.filename();
  if (nested.size() > 1) {
    FailInput(dir, "its subfolders hold several .lp files (" + nested[0].string() + ", " +
                       nested[1].string() + "); name the light file with --lights");
  }
  if (nested.size() == 1) return nested[0];
  const fs::path parent = Absolute(dir).parent_path();
  for (const char* name : {"lights.txt", "light_directions.txt"})
    if (Exists(parent / name)) return (dir / ".." / name).lexically_normal();
  std::vector<std::string> parent_files;
  std::error_code error;
  for (fs::directory_iterator it(parent, error), end; !error && it != end; it.increment(error)) {
    if (Lower(it->path().extension().string()) == ".lp") {
      parent_files.push_back(it->path().filename().string());
    }
    if (parent_files.size() > 1) break;
  }
  if (parent_files.size() == 1) return (dir / ".." / parent_files[0]).lexically_normal();
  FailInput(dir,
            "no light directions: found no light_directions.txt, lights.txt, lights.json or .lp "
            "file here or in the parent folder; name one with --lights FILE");
}

// An image a .lp names (io/image_list.h's rule).
fs::path ResolveLpImage(const std::string& name, const fs::path& lp, const fs::path& dir) {
  fs::path found = ResolveListedImage(name, lp, dir);
  if (found.empty()) {
    FailInput(lp, ListedImageMissing(name, lp, dir));
  }
  return found;
}

std::string Range(const std::vector<std::string>& names) {
  if (names.empty()) return "none";
  if (names.size() == 1) return names[0];
  return names.front() + (names.size() == 2 ? ", " : " ... ") + names.back();
}

}  // namespace

bool NaturalLess(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i]));
    const bool db = std::isdigit(static_cast<unsigned char>(b[j]));
    if (da && db) {
      std::size_t ei = i, ej = j;
      while (ei < a.size() && std::isdigit(static_cast<unsigned char>(a[ei]))) ++ei;
      while (ej < b.size() && std::isdigit(static_cast<unsigned char>(b[ej]))) ++ej;
      std::size_t si = i, sj = j;  // leading zeros do not change the number
      while (si + 1 < ei && a[si] == '0') ++si;
      while (sj + 1 < ej && b[sj] == '0') ++sj;
      if (ei - si != ej - sj) return ei - si < ej - sj;
      if (const int c = a.compare(si, ei - si, b, sj, ej - sj); c != 0) return c < 0;
      i = ei;
      j = ej;
      continue;
    }
    const char ca = static_cast<char>(std::tolower(static_cast<unsigned char>(a[i])));
    const char cb = static_cast<char>(std::tolower(static_cast<unsigned char>(b[j])));
    if (ca != cb) return ca < cb;
    ++i;
    ++j;
  }
  if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
  return a < b;  // equal up to case and zeros: any fixed order
}

// The last part of a file's stem after a '.', '_' or '-' ("albedo" of "buddha.albedo.tga").
std::string LastStemPart(const std::string& name) {
  const std::string stem = Lower(Stem(name));
  const std::size_t cut = stem.find_last_of("._-");
  return cut == std::string::npos ? stem : stem.substr(cut + 1);
}

int MaskNameRank(const std::string& name) {
  if (!HasImageExtension(name)) return -1;
  const std::string stem = Lower(Stem(name));
  if (stem == "mask") return 0;
  return stem.size() > 5 && LastStemPart(name) == "mask" ? 1 : -1;
}

bool IsCompanionImage(const std::string& name) {
  static const std::set<std::string> kStems = {
      "normal_gt", "normals", "normal", "depth",     "depths",   "albedo",   "residual",
      "specular",  "error",   "height", "ambiguity", "clusters", "thumbnail"};
  return MaskNameRank(name) >= 0 || kStems.count(Lower(Stem(name))) > 0 ||
         kStems.count(LastStemPart(name)) > 0;
}

bool HasImageExtension(const std::string& name) {
  static const std::set<std::string> kExtensions = {
      ".png", ".jpg", ".jpeg", ".tif",  ".tiff", ".tga", ".exr", ".bmp", ".ppm",
      ".pgm", ".pnm", ".hdr",  ".webp", ".jp2",  ".dpx", ".pfm", ".sgi", ".rgb"};
  return kExtensions.count(Lower(fs::path(name).extension().string())) > 0;
}

std::string CaptureOptions::Check() const {
  if (encoding != "auto" && encoding != "linear" && encoding != "srgb") {
    return "encoding must be auto, linear or srgb (got " + encoding + ")";
  }
  if (downscale < 1 || downscale > 64) return "downscale must be 1 to 64";
  if (crop.width != 0 || crop.height != 0 || crop.x != 0 || crop.y != 0) {
    if (crop.width <= 0 || crop.height <= 0 || crop.x < 0 || crop.y < 0) {
      return "crop must be x,y,w,h with x, y >= 0 and w, h > 0";
    }
  }
  return "";
}

CaptureFiles FindCapture(const std::string& directory, const CaptureOptions& options) {
  if (std::string m = options.Check(); !m.empty()) throw std::invalid_argument(m);
  const fs::path dir(directory);
  CaptureFiles c;
  c.directory = directory;
  const std::vector<std::string> files = FolderFiles(dir);

  // The images, and the lights when the list gives them.
  fs::path light_file = options.lights.empty() ? fs::path() : fs::path(options.lights);
  std::string listed_mask;  // a mask the image list names
  // The photos as a list names them: count line, paths, the mask among them (UW's).
  auto take_list = [&](const fs::path& list) {
    ImageList read = ReadImageList(list, dir);
    c.layout = "listed";
    c.names = std::move(read.names);
    c.paths = std::move(read.paths);
    c.order = list.string();
    listed_mask = read.mask_path;
  };
  // A folder with nothing to read says so, before any light file is looked for.
  const std::string own_list = Absolute(dir).filename().string() + ".txt";
  if (options.images.empty() && !Exists(dir / "filenames.txt") &&
      std::none_of(files.begin(), files.end(),
                   [](const std::string& name) {
                     return HasImageExtension(name) ||
                            Lower(fs::path(name).extension().string()) == ".lp";
                   }) &&
      !LooksLikeImageList((dir / ".." / own_list).lexically_normal())) {
    FailInput(dir,
              "holds no images (no image files, filenames.txt or .lp): is it the capture's "
              "folder?");
  }
  if (!options.images.empty()) {
    if (light_file.empty() && options.lights_needed) light_file = FindLightFile(dir, files);
    take_list(options.images);
    if (Lower(light_file.extension().string()) == ".lp") c.layout = "RTI .lp, listed";
  } else if (Exists(dir / "filenames.txt")) {
    c.layout = "DiLiGenT";
    const fs::path list = dir / "filenames.txt";
    c.names = ParseFilenames(ReadTextFile(list.string()), list.string());
    c.order = "filenames.txt";
    // A near-light capture may give positions alone.
    if (light_file.empty() && options.lights_needed &&
        (Exists(dir / "light_directions.txt") || !Exists(dir / "light_positions.txt"))) {
      light_file = dir / "light_directions.txt";
    }
  } else {
    if (light_file.empty() && options.lights_needed) light_file = FindLightFile(dir, files);
    // <folder>.txt or images.txt here, or UW's <folder>.txt one folder up.
    fs::path list;
    for (const fs::path& candidate :
         {dir / own_list, dir / "images.txt", (dir / ".." / own_list).lexically_normal()})
      if (list.empty() && LooksLikeImageList(candidate)) list = candidate;
    if (Lower(light_file.extension().string()) == ".lp") {
      c.layout = "RTI .lp";
    } else if (!list.empty()) {
      take_list(list);
    } else {
      c.layout = "folder";
      // A mask named with --mask may sit among the images under any name.
      auto named_mask = [&](const std::string& name) {
        std::error_code e;
        return !options.mask.empty() && fs::equivalent(dir / name, options.mask, e);
      };
      for (const std::string& name : files) {
        if (!HasImageExtension(name) || named_mask(name) || MaskNameRank(name) >= 0) continue;
        if (!IsCompanionImage(name)) c.names.push_back(name);
      }
      c.order = "natural order";
      if (c.names.empty()) FailInput(dir, "holds no image files (and no filenames.txt)");
    }
  }

  // The light directions.
  c.lights_path = light_file.string();
  std::vector<std::string>* warnings = &c.warnings;
  if (!options.lights_needed) {
    c.lights_format = "none (not needed)";
  } else if ((c.layout == "DiLiGenT" && light_file.empty()) ||
             light_file.filename() == "light_positions.txt") {
    // Positions alone: the dataset's own, or a rig's named with --lights (calibrate-lights
    // writes them with camera.json beside them), in the order of the images.
    if (c.names.empty()) {
      for (const std::string& name : files)
        if (HasImageExtension(name) && !IsCompanionImage(name)) c.names.push_back(name);
      c.order = "natural order";
    }
    const std::string rig =
        light_file.empty() ? directory : Absolute(light_file).parent_path().string();
    c.near = FindNearLights(rig, c.names.size(), warnings);
    if (!c.near.present()) FailInput(light_file, "no such file");
    c.light_directions = DirectionsFromPositions(c.near);
    c.lights_path = c.near.positions_path;
    c.lights_format = "positions (near lights)";
    // The rig's intensities when the dataset has none of its own.
    if (options.intensities.empty() && !Exists(dir / "light_intensities.txt") &&
        Exists(fs::path(rig) / "light_intensities.txt")) {
      const fs::path rig_intensities = fs::path(rig) / "light_intensities.txt";
      c.light_intensities = ParseLightIntensities(ReadTextFile(rig_intensities.string()),
                                                  rig_intensities.string(), c.names.size());
      c.intensities_source = rig_intensities.string();
      c.intensities_from_file = true;
    }
  } else if (c.layout == "DiLiGenT" && options.lights.empty()) {
    c.light_directions =
        ParseLightDirections(ReadTextFile(c.lights_path), c.lights_path, c.names.size(), warnings);
    c.lights_format = "directions";
  } else {
    LightFile lights = ParseLightFile(ReadTextFile(c.lights_path), c.lights_path, 0, warnings);
    c.lights_format = lights.format;
    c.light_directions = std::move(lights.directions);
    if (!lights.intensities.empty()) {
      c.light_intensities = std::move(lights.intensities);
      c.intensities_source = c.lights_path;
      c.intensities_from_file = true;
    }
    if (!lights.image_names.empty() && c.names.empty()) {  // RTI: the .lp names the images
      c.names = lights.image_names;
      c.order = light_file.filename().string();
      for (const std::string& name : c.names) {
        c.paths.push_back(ResolveLpImage(name, light_file, dir).string());
      }
    }
    if (c.names.size() != c.light_directions.size()) {
      FailInput(c.lights_path,
                "has " + std::to_string(c.light_directions.size()) + " lights, but " + directory +
                    " holds " + std::to_string(c.names.size()) + " images (" + Range(c.names) +
                    "): a light missing from the file or a photo too many; to choose "
                    "the photos, list them in light order in a file given with "
                    "--images LIST");
    }
  }
  if (options.lights_needed && !c.near.present()) {
    c.near = FindNearLights(directory, c.names.size(), warnings);
    if (c.near.present()) {
      // Both files: the same lights, seen from one point (the object's).
      std::vector<int> lines(c.light_directions.size());
      for (std::size_t j = 0; j < lines.size(); ++j) lines[j] = static_cast<int>(j + 1);
      CheckDirectionsAgree(c.near, c.light_directions, c.lights_path, lines);
      c.lights_format += " with positions (near lights)";
    }
  }
  // A camera file beside light directions (a renderer's perspective camera and sun lamps) is not
  // used: said, so the user does not take the view for a perspective one.
  if (options.lights_needed && !c.near.present() && Exists(dir / "camera.json")) {
    c.warnings.push_back((dir / "camera.json").string() +
                         ": not read: a camera is read with light_positions.txt (near lights); "
                         "under light directions every pixel is seen along the optical axis "
                         "(V = (0, 0, 1), an orthographic view)");
  }
  if (c.paths.empty()) {
    for (const std::string& name : c.names) c.paths.push_back((dir / name).string());
  }
  if (c.paths.empty()) FailInput(dir, "holds no images");  // every reader above needs at least one
  // One image under two lights is a slip in the list (the same line pasted twice): the run goes
  // on, as the observations are still valid for one of the lights, but says so.
  {
    std::map<std::string, std::vector<std::size_t>> entries;  // each image's places in the list
    for (std::size_t j = 0; j < c.paths.size(); ++j)
      entries[fs::path(c.paths[j]).lexically_normal().string()].push_back(j);
    std::size_t repeated = 0, first = c.paths.size(), times = 0;
    for (const auto& [path, at] : entries) {
      if (at.size() < 2) continue;
      repeated += at.size();
      if (at[0] < first) first = at[0], times = at.size();
    }
    if (repeated > 0) {
      const std::string example = c.names[first] + " " + std::to_string(times) + " times";
      const fs::path list = c.layout == "folder"                           ? dir
                            : c.layout.find("listed") != std::string::npos ? fs::path(c.order)
                                                                           : dir / c.order;
      c.warnings.push_back(list.string() + ": lists " + example + " (" + std::to_string(repeated) +
                           " of " + std::to_string(c.paths.size()) +
                           " entries name an image listed more than once): each light needs its "
                           "own photograph");
    }
  }

  // Intensities.
  fs::path intensities = options.intensities;
  if (!options.lights_needed) {
    c.light_intensities.assign(c.names.size(), Vec3d::Ones());
    c.intensities_source = "not read (not needed)";
  } else if (options.intensities == kNoIntensities) {
    // The capture's own file (or the .lp's, the rig's) set aside without touching the folder.
    c.light_intensities.assign(c.names.size(), Vec3d::Ones());
    c.intensities_source = "all 1 (--intensities none)";
    c.intensities_from_file = false;
    intensities.clear();
  } else if (intensities.empty() && Exists(dir / "light_intensities.txt")) {
    intensities = dir / "light_intensities.txt";
  }
  if (options.lights_needed && !intensities.empty()) {
    c.light_intensities = ParseLightIntensities(ReadTextFile(intensities.string()),
                                                intensities.string(), c.names.size());
    c.intensities_source = intensities.string();
    c.intensities_from_file = true;
  } else if (c.light_intensities.empty()) {
    c.light_intensities.assign(c.names.size(), Vec3d::Ones());
    c.intensities_source = "all 1 (no light_intensities.txt)";
  }

  // Mask.
  if (!options.mask.empty()) {
    c.mask_path = options.mask;
  } else if (!listed_mask.empty()) {
    c.mask_path = listed_mask;
  } else if (Exists(dir / "mask.png")) {
    c.mask_path = (dir / "mask.png").string();
  } else {
    int best = 2;
    for (const std::string& name : files) {
      const int rank = MaskNameRank(name);
      if (rank >= 0 && rank < best) {
        best = rank;
        c.mask_path = (dir / name).string();
      }
    }
  }

  for (const char* name : {"Normal_gt.mat", "normal.txt"}) {
    if (c.ground_truth_path.empty() && Exists(dir / name))
      c.ground_truth_path = (dir / name).string();
  }
  // What the folder holds beside the photos and is not read (UW's albedo picture, normals.dat
  // and depths.dat; iphong's own outputs), so the user sees it was not taken for a photo.
  {
    std::set<std::string> used;
    for (const std::string& path : c.paths) used.insert(fs::path(path).filename().string());
    for (const std::string& name : files) {
      const bool kind =
          HasImageExtension(name) || Lower(fs::path(name).extension().string()) == ".dat";
      if (kind && IsCompanionImage(name) && MaskNameRank(name) < 0 && !used.count(name) &&
          (dir / name).string() != c.mask_path)
        c.skipped.push_back(name);
    }
  }
  if (Exists(dir / "material.json")) c.material_path = (dir / "material.json").string();
  if (Exists(dir / "render.json")) c.render_json = (dir / "render.json").string();
  return c;
}

EncodingChoice ChooseEncoding(const CaptureFiles& files, const CaptureOptions& options,
                              const StoredEncoding& first) {
  if (options.encoding == "linear") return {Encoding::kLinear, "--encoding linear"};
  if (options.encoding == "srgb") return {Encoding::kSrgb, "--encoding srgb"};
  if (!files.render_json.empty()) {
    const std::string text = ReadTextFile(files.render_json);
    const nlohmann::json document = JsonReader::Parse(text, files.render_json);
    const JsonReader j(document, files.render_json);
    const std::string encoding = j.String("encoding", "linear");
    if (encoding != "linear" && encoding != "srgb") {
      j.Field("encoding").Fail("expected linear or srgb");
    }
    return {encoding == "srgb" ? Encoding::kSrgb : Encoding::kLinear, "render.json says so"};
  }
  const std::string what = std::to_string(first.bits) + "-bit " + first.format;
  if (first.header.is_float) return {Encoding::kLinear, what + " (float)"};
  if (first.stated) return {first.encoding, what + " states it (" + first.statement + ")"};
  // 16-bit files are raw camera data far more often than pictures made for a screen.
  return {Encoding::kLinear,
          what + " states no colour space" +
              (first.bits <= 8 ? "; --encoding srgb if display-encoded" : ""),
          true};
}

}  // namespace iphong::io
