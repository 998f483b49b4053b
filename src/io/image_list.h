// An image list: a text file naming a capture's photographs in light order, one per line, as
// DiLiGenT's filenames.txt, UW's <object>.txt (one folder up from the photos, a count line first,
// paths relative to wherever the course's code ran, the mask last) and `--images LIST` give them.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace iphong::io {

struct ImageList {
  std::string path;                // the list file
  std::vector<std::string> names;  // the photos' entries as written, in light order
  std::vector<std::string> paths;  // each found: as written relative to the list's folder or the
                                   // capture's, else by its base name there
  std::string mask_path;           // an entry that names a mask (io/capture.h's rule), or ""
  std::size_t line_of_first = 0;   // 1-based line of the first photo
};

// Whether `file` reads as a list of images: its first line that is not a count names an image
// (by extension). False for a missing or unreadable file.
bool LooksLikeImageList(const std::filesystem::path& file);

// Throws std::runtime_error naming the list (and line): no photos, an entry found nowhere, a
// count line other than the number of photos (or of entries).
ImageList ReadImageList(const std::filesystem::path& list,
                        const std::filesystem::path& capture_dir);

// An entry of a list or .lp: `name` as written relative to `list`'s folder or `capture_dir`, else
// its base name in either (RTIBuilder writes absolute Windows paths of the machine it ran on; UW's
// lists paths from the course's folder). Empty when none exists.
std::filesystem::path ResolveListedImage(const std::string& name, const std::filesystem::path& list,
                                         const std::filesystem::path& capture_dir);
// "names NAME, which is not in DIR" (or "in neither LIST_DIR nor DIR"): the error when
// ResolveListedImage finds nothing, naming each folder it looked in once.
std::string ListedImageMissing(const std::string& name, const std::filesystem::path& list,
                               const std::filesystem::path& capture_dir);

}  // namespace iphong::io
