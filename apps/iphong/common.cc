// Flags and checks the subcommands share.
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "geometry/height_map.h"
#include "iphong/commands.h"
#include "iphong/console.h"

namespace iphong::cli {
namespace fs = std::filesystem;

const CLI::Validator& Positive() {
  static const CLI::Validator validator(
      [](std::string& text) -> std::string {
        double value = 0;
        if (!CLI::detail::lexical_cast(text, value) || !(value > 0) || !std::isfinite(value)) {
          return "must be a number > 0 (got " + text + ")";
        }
        return "";
      },
      "POSITIVE");
  return validator;
}

const CLI::Validator& Scale() {
  static const CLI::Validator validator(
      [](std::string& text) -> std::string {
        double value = 0;
        if (!CLI::detail::lexical_cast(text, value) || !geometry::ScaleInRange(value)) {
          return "must be a number between 1e-12 and 1e12 (got " + text + ")";
        }
        return "";
      },
      "1e-12..1e12");
  return validator;
}

void AddThreadsOption(CLI::App* cmd, CommonOptions& common) {
  cmd->add_option("--threads", common.threads, "Threads (0 = all cores)")
      ->check(CLI::Range(0, 1024));
}

void AddMemoryOption(CLI::App* cmd, CommonOptions& common) {
  cmd->add_option_function<std::string>(
         "--memory-limit,--max-memory",
         [&common](const std::string& text) {
           std::uint64_t bytes = 0;
           if (std::string m = ParseMemorySize(text, &bytes); !m.empty())
             throw CLI::ValidationError("--memory-limit", m);
           common.memory_limit_bytes = bytes;
         },
         "Memory to stay within: 16 or 16GB, 512MB, 1.5GiB (a plain number is GB; default: 3/4 "
         "of the machine's, or of ulimit -v): work that needs more is refused before it starts "
         "(exit 3), except normals, which then reads and solves the capture in bands of rows "
         "that fit")
      ->type_name("SIZE");
}

void AddOverwriteOption(CLI::App* cmd, CommonOptions& common) {
  cmd->add_flag("--overwrite", common.overwrite,
                "Replace the files of an earlier output of this command in -o (only those; "
                "nothing else in the folder is touched)");
}

void AddReportOptions(CLI::App* cmd, CommonOptions& common) {
  cmd->add_option("--progress", common.progress,
                  "Progress of long stages on stderr: auto (a bar on a terminal; in a log or "
                  "pipe a line every 10 s once a stage passes 10 s), always (lines every 2 s, "
                  "also with --json), never")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", common.quiet, "Print nothing but errors and warnings");
  cmd->add_flag("--json", common.json,
                "Print the run's summary as one JSON document on stdout (for scripts)");
}

void AddCaptureOptions(CLI::App* cmd, CaptureFlags& f) {
  cmd->add_option("--lights", f.options.lights,
                  "Light file: directions per line, UW lights.txt (count line), RTI .lp, or "
                  "AliceVision lights JSON (default: found in the folder or its parent)");
  cmd->add_option("--intensities", f.options.intensities,
                  "Light intensities, 'r g b' per light (default: light_intensities.txt, else 1; "
                  "'none': all 1, whatever intensity file the capture holds)");
  cmd->add_option("--images", f.options.images,
                  "A text file naming the photos in light order, one per line (default: "
                  "filenames.txt, the .lp, FOLDER.txt here or one folder up, images.txt; else "
                  "the folder's images in natural order)");
  cmd->add_option("--mask", f.options.mask,
                  "Mask picture, nonzero = object (default: mask.png, mask.*, NAME.mask.*, "
                  "NAME_mask.*; else the whole image)");
  cmd->add_option("--encoding", f.options.encoding,
                  "How the image values are encoded: auto (what the files state, else linear; "
                  "normals warns when the data look display-encoded), linear, srgb")
      ->check(CLI::IsMember({"auto", "linear", "srgb"}))
      ->capture_default_str();
  cmd->add_option("--crop", f.crop,
                  "Use only this rectangle of the images, mask and ground truth: x,y,w,h in the "
                  "files' pixels (applied before --downscale)")
      ->delimiter(',')
      ->expected(4);
  cmd->add_option("--downscale", f.options.downscale,
                  "Average N x N pixel blocks (images, mask, ground truth) before anything else")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
}

io::CaptureOptions CaptureFlags::resolved() const {
  io::CaptureOptions o = options;
  if (crop.size() == 4) {
    // 0,0,0,0 is the options' "no crop": given, it is a rectangle of no pixels.
    if (crop[2] <= 0 || crop[3] <= 0) {
      throw CLI::ValidationError("--crop", "x,y,w,h needs w, h > 0 (got " +
                                               std::to_string(crop[2]) + "x" +
                                               std::to_string(crop[3]) + ")");
    }
    o.crop = {crop[0], crop[1], crop[2], crop[3]};
  }
  if (std::string m = o.Check(); !m.empty()) throw CLI::ValidationError("--crop", m);
  return o;
}

void Say(const CommonOptions& common, const char* format, ...) {
  if (!common.talk()) return;
  va_list args;
  va_start(args, format);
  std::vfprintf(stdout, format, args);
  va_end(args);
}

void PrintJson(const CommonOptions& common, const std::string& json_text) {
  if (common.json) std::printf("%s\n", json_text.c_str());
}

void RequireFolder(const std::string& path) {
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (!fs::exists(status)) throw std::runtime_error(path + ": no such folder");
  if (!fs::is_directory(status)) throw std::runtime_error(path + ": is a file, not a folder");
}

}  // namespace iphong::cli

namespace iphong::cli {

io::ObservationSet LoadCaptureObservations(const std::string& folder, const CaptureFlags& capture,
                                           const CommonOptions& common) {
  io::DatasetLoadOptions load;
  load.capture = capture.resolved();
  load.threads = common.threads;
  load.memory = common.memory();
  Progress decode("decode", common.progress_mode());
  load.progress = [&decode](double fraction) { decode.Update(fraction); };
  return io::LoadObservations(folder, load);
}

void ReportCapture(const std::string& folder, const io::Dataset& dataset,
                   const CommonOptions& common) {
  Say(common, "Read %s: %s\n", folder.c_str(), io::DescribeDataset(dataset).c_str());
  for (const std::string& warning : dataset.warnings) Warn(warning);
  if (std::string counts = io::DescribeImageCounts(dataset); !counts.empty()) Warn(counts);
}

}  // namespace iphong::cli
