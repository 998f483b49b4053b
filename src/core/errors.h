// What went wrong, by kind, so the command line can choose its exit code and Python its
// exception (docs/cli.md, "Errors and exit codes"):
//
//   std::runtime_error, invalid_argument   bad input (a file or value)    exit 1, ValueError
//   ResourceError                          over the memory limit          exit 3, ValueError
//   OutputError                            the output cannot be written   exit 4, OSError
//
// Every message is one line that starts with the file (and line, or field) it is about.
#pragma once

#include <stdexcept>
#include <string>

namespace iphong {

struct ResourceError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A bad input: throws std::runtime_error "SOURCE:LINE: message" (line 0: "SOURCE: message").
[[noreturn]] inline void FailInput(const std::string& source, const std::string& message,
                                   int line = 0) {
  throw std::runtime_error(source + (line > 0 ? ":" + std::to_string(line) : "") + ": " + message);
}

// Messages from libraries may span lines (OpenImageIO's do) and may quote bytes of a broken
// input; iphong prints one line of valid UTF-8 per error: control characters become spaces,
// runs of spaces one, bytes that are not UTF-8 '?'.
inline std::string OneLine(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      const char plain = c < 0x20 || c == 0x7f ? ' ' : static_cast<char>(c);
      if (!(plain == ' ' && (out.empty() || out.back() == ' '))) out += plain;
      ++i;
      continue;
    }
    // A well-formed multi-byte sequence is kept whole.
    const int length = c >= 0xf0 && c <= 0xf4 ? 4 : c >= 0xe0 ? 3 : c >= 0xc2 && c < 0xe0 ? 2 : 0;
    bool valid = length > 0 && i + length <= text.size();
    for (int k = 1; valid && k < length; ++k) {
      valid = (static_cast<unsigned char>(text[i + k]) & 0xc0) == 0x80;
    }
    if (valid) {
      out.append(text, i, length);
      i += length;
    } else {
      out += '?';
      ++i;
    }
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

}  // namespace iphong
