// How iphong talks to the person running it, and how it stops.
//
// stderr carries iphong's own lines only: exactly one per error, warnings, progress. The libraries
// linked in (libpng inside OpenImageIO, OpenMesh, matio, glog inside Ceres) print lines of their
// own, so SetUpConsole keeps the real stderr for iphong and points file descriptor 2 at /dev/null;
// IPHONG_LIBRARY_STDERR=1 leaves it alone, for debugging.
//
// SIGINT, SIGTERM and SIGHUP are taken by one thread: it removes the unfinished output (waiting
// for a commit in progress to finish), says so on one line and ends the process by the same
// signal, so the shell sees 130/143/129. SIGXFSZ is ignored, so a file-size limit surfaces as
// a write error (exit 4) instead of killing the process.
#pragma once

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

namespace iphong::cli {

// Call first in main, before any thread starts (the signal mask is inherited).
void SetUpConsole();

FILE* Err();  // iphong's stderr
// True once SIGINT, SIGTERM or SIGHUP arrived: the watcher thread removes the unfinished
// outputs, says so and ends the process with the signal. The main thread then waits for it
// (AwaitInterrupt) instead of reporting the errors the removal causes in the writers.
bool Interrupted();
[[noreturn]] void AwaitInterrupt();
bool ErrIsTerminal();                   // progress is shown only on a terminal
void Warn(const std::string& message);  // "iphong: warning: MESSAGE"

// One stage's progress on stderr. On a terminal, one line rewritten in place once the stage has
// run for a second, at most ten times a second, cleared when the stage ends:
//   "fit: 61% (22816/37068 pixels), 1.4 s, about 0.9 s left"
// Otherwise whole lines "iphong: fit: 61% (...), 14 s, about 9 s left" and "iphong: fit: done,
// 23 s", as the mode says. Update may be called from any thread.
enum class ProgressMode {
  kNever,
  kAuto,    // a bar on a terminal; otherwise plain lines every 10 s once a stage passes 10 s
  kAlways,  // a bar on a terminal; otherwise a line at a stage's start, then every 2 s
};

class Progress {
 public:
  Progress(std::string stage, ProgressMode mode, std::string unit = "", double total = 0);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void Update(double fraction);
  void Count(double done);  // done out of `total` units

 private:
  std::string stage_, unit_;
  double total_;
  bool bar_ = false, lines_ = false;  // a bar on a terminal, or plain lines in a log
  bool always_ = false;               // --progress always: every stage is shown, however short
  double line_interval_ = 10;         // seconds between plain lines (and before the first)
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_, last_;
  std::mutex mutex_;
};

}  // namespace iphong::cli
