// What went wrong, by kind, so the command line can choose its exit code and Python its exception
// (README, "Command line"):
//   std::runtime_error / std::invalid_argument  bad input: a file or value is wrong   exit 1,
//   ValueError ResourceError                               the request exceeds the memory limit
//   exit 3, ValueError OutputError                                 the output cannot be written
//   exit 4, OSError
// Every message is one line that starts with the file (and line, or field) it is about.
#pragma once

#include <stdexcept>

namespace iphong {

struct ResourceError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace iphong

#include <string>

namespace iphong {

// Messages from libraries may span lines (OpenImageIO's do); iphong prints one line per error.
inline std::string OneLine(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  }
  std::string out;
  for (char c : text) {
    if (c == ' ' && (out.empty() || out.back() == ' ')) continue;
    out += c;
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

}  // namespace iphong
