// The iphong subcommands. Each one adds itself to the CLI11 app: parse flags into an options
// struct, make one library call, write the outputs.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "core/resources.h"
#include "io/capture.h"
#include "io/dataset.h"
#include "iphong/console.h"

namespace iphong::cli {

// Exit codes (docs/cli.md, "Errors and exit codes"); a signal ends the process as that signal (128
// + n).
constexpr int kExitInput = 1;      // a file or value is wrong
constexpr int kExitUsage = 2;      // the command line is wrong
constexpr int kExitResources = 3;  // the request exceeds the memory limit
constexpr int kExitOutput = 4;     // the output cannot be written (folder refused, disk full)
constexpr int kExitInternal = 70;  // a bug in iphong
constexpr const char* kExitCodes =
    "Exit codes: 0 done; 1 bad input (a file or value); 2 bad command line; 3 over the memory "
    "limit (--memory-limit); 4 output not written (folder refused, disk full); 70 internal error; "
    "130/143 interrupted (SIGINT/SIGTERM). An error is one line on stderr, naming the file; a "
    "failed or interrupted run leaves its output folder as it was.";

// A number > 0; the message says so (CLI11's PositiveNumber prints the whole double range).
const CLI::Validator& Positive();
// A scale (a pixel size, a focal length) in [1e-12, 1e12], the range float results keep.
const CLI::Validator& Scale();

// Flags most commands share.
struct CommonOptions {
  int threads = 0;
  std::uint64_t memory_limit_bytes = 0;  // 0 = three quarters of the machine's memory
  bool overwrite = false;
  bool quiet = false;  // nothing on stdout, no progress; errors and warnings still on stderr
  bool json = false;   // the run's summary as JSON on stdout, nothing else there

  // --progress: "auto" (a bar on a terminal; in a log, a plain line every 10 s once a stage
  // passes 10 s), "always" (also with --json; lines every 2 s), "never".
  std::string progress = "auto";

  bool talk() const { return !quiet && !json; }  // human-readable lines and progress
  ProgressMode progress_mode() const {
    if (quiet || progress == "never") return ProgressMode::kNever;
    if (progress == "always") return ProgressMode::kAlways;
    return json ? ProgressMode::kNever : ProgressMode::kAuto;
  }

  MemoryLimit memory() const {
    MemoryLimit limit;
    limit.bytes = memory_limit_bytes;
    return limit;
  }
};
void AddThreadsOption(CLI::App* cmd, CommonOptions& common);
void AddMemoryOption(CLI::App* cmd, CommonOptions& common);
void AddOverwriteOption(CLI::App* cmd, CommonOptions& common);
void AddReportOptions(CLI::App* cmd, CommonOptions& common);  // --quiet, --json

// --lights, --intensities, --mask, --encoding, --crop, --downscale: how a capture folder is read.
struct CaptureFlags {
  io::CaptureOptions options;
  std::vector<int> crop;  // x, y, w, h
  io::CaptureOptions resolved() const;
};
void AddCaptureOptions(CLI::App* cmd, CaptureFlags& flags);

// The masked pixels of a capture folder's images as the solvers take them (io::LoadObservations),
// with the decode progress on a terminal.
io::ObservationSet LoadCaptureObservations(const std::string& folder, const CaptureFlags& capture,
                                           const CommonOptions& common);
// "Read FOLDER: what was read", then the reader's warnings and the clipped/black image counts.
void ReportCapture(const std::string& folder, const io::Dataset& dataset,
                   const CommonOptions& common);

// printf to stdout when the run talks (not --quiet, not --json).
void Say(const CommonOptions& common, const char* format, ...)
    __attribute__((format(printf, 2, 3)));

// With --json, the summary on stdout (one JSON document).
void PrintJson(const CommonOptions& common, const std::string& json_text);

// A one-line error naming the path unless it is a folder: "PATH: no such folder", "PATH: is a
// file, not a folder". (Files need no such check: every reader in io makes it.)
void RequireFolder(const std::string& path);

void AddDemoCommand(CLI::App& app);
void AddMaterialsCommand(CLI::App& app);
void AddRenderCommand(CLI::App& app);
void AddNormalsCommand(CLI::App& app);
void AddEvalCommand(CLI::App& app);
void AddIntegrateCommand(CLI::App& app);
void AddCalibrateCommand(CLI::App& app);  // calibrate-lights
void AddFitMaterialCommand(CLI::App& app);
void AddRelightCommand(CLI::App& app);

// Every subcommand, in the order `iphong --help` lists them. New commands are added here only.
inline void AddAllCommands(CLI::App& app) {
  AddDemoCommand(app);
  AddRenderCommand(app);
  AddCalibrateCommand(app);
  AddNormalsCommand(app);
  AddEvalCommand(app);
  AddIntegrateCommand(app);
  AddFitMaterialCommand(app);
  AddRelightCommand(app);
  AddMaterialsCommand(app);
}

}  // namespace iphong::cli
