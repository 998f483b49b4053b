#include "io/image_list.h"

#include <stdexcept>

#include "io/capture.h"
#include "io/dataset_text.h"
#include "io/files.h"

namespace iphong::io {
namespace fs = std::filesystem;

namespace {

bool IsCount(const std::string& entry) {
  return !entry.empty() && entry.size() <= 9 &&
         entry.find_first_not_of("0123456789") == std::string::npos;
}

}  // namespace

fs::path ResolveListedImage(const std::string& name, const fs::path& list,
                            const fs::path& capture_dir) {
  std::string base = name;
  if (const std::size_t cut = base.find_last_of("/\\"); cut != std::string::npos) {
    base = base.substr(cut + 1);
  }
  for (const fs::path& candidate : {list.parent_path() / name, capture_dir / name,
                                    list.parent_path() / base, capture_dir / base}) {
    if (Exists(candidate)) return candidate.lexically_normal();
  }
  return {};
}

bool LooksLikeImageList(const fs::path& file) {
  std::error_code error;
  if (!fs::is_regular_file(file, error) || fs::file_size(file, error) > (1u << 24)) return false;
  try {
    const std::vector<std::string> entries =
        ParseFilenames(ReadTextFile(file.string()), file.string());
    const std::size_t first = IsCount(entries.front()) ? 1 : 0;
    return first < entries.size() && HasImageExtension(entries[first]);
  } catch (const std::exception&) {
    return false;
  }
}

std::string ListedImageMissing(const std::string& name, const fs::path& list,
                               const fs::path& capture_dir) {
  const fs::path here = list.parent_path();
  std::error_code error;
  const bool same = here == capture_dir || fs::equivalent(here, capture_dir, error);
  return "names " + name + ", which is " +
         (same ? "not in " + capture_dir.string()
               : "in neither " + here.string() + " nor " + capture_dir.string());
}

ImageList ReadImageList(const fs::path& list, const fs::path& capture_dir) {
  ImageList out;
  out.path = list.string();
  // Read once: the same text gives the entries and their line numbers.
  const std::string text = ReadTextFile(out.path);
  const std::vector<std::string> entries = ParseFilenames(text, out.path);
  // ParseFilenames keeps non-blank lines only; their line numbers are recovered for messages.
  std::vector<std::size_t> lines;
  {
    std::size_t number = 0, start = 0;
    while (start <= text.size() && lines.size() < entries.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      ++number;
      if (text.substr(start, end - start).find_first_not_of(" \t\r\xEF\xBB\xBF") !=
          std::string::npos)
        lines.push_back(number);
      start = end + 1;
    }
    while (lines.size() < entries.size()) lines.push_back(number);
  }
  const bool counted = IsCount(entries.front());
  std::size_t masks = 0;
  for (std::size_t i = counted ? 1 : 0; i < entries.size(); ++i) {
    const std::string& name = entries[i];
    const fs::path found = ResolveListedImage(name, list, capture_dir);
    if (found.empty()) {
      throw std::runtime_error(out.path + ":" + std::to_string(lines[i]) + ": " +
                               ListedImageMissing(name, list, capture_dir));
    }
    if (MaskNameRank(found.filename().string()) >= 0) {
      if (++masks > 1) {
        throw std::runtime_error(out.path + ":" + std::to_string(lines[i]) +
                                 ": names a second mask (" + name + ")");
      }
      out.mask_path = found.string();
      continue;
    }
    if (out.names.empty()) out.line_of_first = lines[i];
    out.names.push_back(name);
    out.paths.push_back(found.string());
  }
  if (out.names.empty()) throw std::runtime_error(out.path + ": lists no photographs");
  if (counted) {
    const std::size_t count = std::stoul(entries.front());
    if (count != out.names.size() && count != out.names.size() + masks) {
      throw std::runtime_error(out.path + ":" + std::to_string(lines[0]) + ": says " +
                               entries.front() + " images, but lists " +
                               std::to_string(out.names.size()) + " photographs" +
                               (masks ? " and a mask" : ""));
    }
  }
  return out;
}

}  // namespace iphong::io
