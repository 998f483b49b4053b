#include "iphong/console.h"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <thread>

#include "core/errors.h"
#include "io/output_folder.h"

namespace iphong::cli {
namespace {

// The process's one console: set once in SetUpConsole, before any other thread exists.
FILE* own_stderr = stderr;
bool own_stderr_tty = false;
// Set by the signal watcher before it removes the outputs: from then on the other threads'
// errors (a writer whose staging folder is gone) are the interrupt's, not the user's.
std::atomic<bool> interrupted{false};

void WaitForSignals(sigset_t signals) {
  int sig = 0;
  if (sigwait(&signals, &sig) != 0) return;
  interrupted = true;
  const io::AbandonReport report = io::AbandonOutputFolders();
  if (report.complete.empty()) {
    std::fprintf(Err(), "iphong: interrupted (%s); %s\n", strsignal(sig),
                 report.removed ? "unfinished output removed" : "nothing was written");
  } else {
    std::string done;
    for (const std::string& t : report.complete) done += (done.empty() ? "" : ", ") + t;
    std::fprintf(Err(), "iphong: interrupted (%s) after the output was complete: %s%s\n",
                 strsignal(sig), OneLine(done).c_str(),
                 report.removed ? " (other unfinished output removed)" : "");
  }
  std::fflush(Err());
  ::signal(sig, SIG_DFL);
  sigset_t one;
  sigemptyset(&one);
  sigaddset(&one, sig);
  pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
  raise(sig);
  std::_Exit(128 + sig);
}

}  // namespace

void SetUpConsole() {
  ::signal(SIGXFSZ, SIG_IGN);
  const char* keep = std::getenv("IPHONG_LIBRARY_STDERR");
  if (!(keep && std::strcmp(keep, "1") == 0)) {
    const int saved = ::fcntl(2, F_DUPFD_CLOEXEC, 3);
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved >= 0 && null >= 0 && ::dup2(null, 2) >= 0) {
      if (FILE* f = ::fdopen(saved, "w")) {
        own_stderr = f;
        std::setvbuf(f, nullptr, _IOLBF, 0);
      }
    }
    if (null >= 0) ::close(null);
  }
  own_stderr_tty = ::isatty(::fileno(own_stderr));
  // An exception nobody caught is a bug, and still gets one line.
  std::set_terminate([] {
    if (interrupted) AwaitInterrupt();
    std::string what = "unknown";
    if (auto p = std::current_exception()) {
      try {
        std::rethrow_exception(p);
      } catch (const std::exception& e) {
        what = e.what();
      } catch (...) {
      }
    }
    std::fprintf(Err(), "iphong: error: internal error (please report it): %s\n",
                 OneLine(what).c_str());
    std::fflush(Err());
    std::_Exit(70);
  });

  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  try {
    std::thread(WaitForSignals, signals).detach();
  } catch (const std::system_error&) {
    pthread_sigmask(SIG_UNBLOCK, &signals, nullptr);  // no watcher: default handling
  }
}

FILE* Err() { return own_stderr; }

bool Interrupted() { return interrupted; }

void AwaitInterrupt() {
  // The watcher ends the process with the signal once the outputs are removed.
  for (;;) ::pause();
}

bool ErrIsTerminal() { return own_stderr_tty; }

Progress::Progress(std::string stage, ProgressMode mode, std::string unit, double total)
    : stage_(std::move(stage)),
      unit_(std::move(unit)),
      total_(total),
      bar_(mode != ProgressMode::kNever && own_stderr_tty),
      lines_(mode != ProgressMode::kNever && !own_stderr_tty),
      always_(mode == ProgressMode::kAlways),
      line_interval_(always_ ? 2 : 10),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

Progress::~Progress() {
  if (!shown_ && !(lines_ && always_)) return;  // an always-shown stage closes even unseen
  if (bar_) {
    std::fprintf(Err(), "\r\033[K");
  } else {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    std::fprintf(Err(), "iphong: %s: done, %.0f s\n", stage_.c_str(), elapsed);
  }
}

void Progress::Count(double done) { Update(total_ > 0 ? done / total_ : 0); }

void Progress::Update(double fraction) {
  if (!bar_ && !lines_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double since = std::chrono::duration<double>(now - last_).count();
  // In a log, --progress always shows a stage's first update at once, so a short stage is seen too.
  const bool first_line = lines_ && always_ && !shown_;
  if (!first_line && (bar_ ? elapsed < 1 || since < 0.1 : since < line_interval_)) return;
  last_ = now;
  shown_ = true;
  fraction = std::min(std::max(fraction, 0.0), 1.0);
  char counts[64] = "";
  if (total_ > 0) {
    std::snprintf(counts, sizeof counts, " (%.0f/%.0f %s)", fraction * total_, total_,
                  unit_.c_str());
  }
  char left[48] = "";
  if (fraction > 0.02) {
    std::snprintf(left, sizeof left, ", about %.0f s left", elapsed * (1 - fraction) / fraction);
  }
  if (bar_) {
    std::fprintf(Err(), "\r\033[K%s: %3.0f%%%s, %.0f s%s", stage_.c_str(), 100 * fraction, counts,
                 elapsed, left);
  } else {  // a log, a pipe, a notebook: whole lines
    std::fprintf(Err(), "iphong: %s: %.0f%%%s, %.0f s%s\n", stage_.c_str(), 100 * fraction, counts,
                 elapsed, left);
  }
  std::fflush(Err());
}

void Warn(const std::string& message) {
  std::fprintf(Err(), "iphong: warning: %s\n", OneLine(message).c_str());
}

}  // namespace iphong::cli
