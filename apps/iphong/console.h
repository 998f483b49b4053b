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

#include <cstdio>
#include <string>

namespace iphong::cli {

// Call first in main, before any thread starts (the signal mask is inherited).
void SetUpConsole();

FILE* Err();                            // iphong's stderr
bool ErrIsTerminal();                   // progress is shown only on a terminal
void Warn(const std::string& message);  // "iphong: warning: MESSAGE"

}  // namespace iphong::cli
