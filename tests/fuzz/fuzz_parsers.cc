// Fuzz target for the text iphong reads: filenames.txt, the light files (every format),
// normal.txt, material.json, scene files, the near-light layout's camera.json and
// light_anisotropy.txt, and the ICC profiles embedded in pictures (binary: it must give a result
// and never throw). The first byte picks the parser, the rest is the text. Every input must end
// in a result or in an exception whose message is one line starting with the file it names;
// anything else (a crash, a sanitizer report, std::bad_alloc, a multi-line or unnamed message) is a
// finding.
//
// Built two ways: with clang's libFuzzer (scripts/fuzz.sh, for long runs by hand) and, with any
// compiler, with fuzz_driver.cc's bounded deterministic mutation (the `fuzz.parsers` test).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "fuzz_parsers.h"
#include "io/dataset_text.h"
#include "io/icc_profile.h"
#include "io/scene_file.h"

namespace {

[[noreturn]] void Finding(const std::string& what, const std::string& input) {
  std::fprintf(stderr, "fuzz finding: %s\ninput (%zu bytes): %s\n", what.c_str(), input.size(),
               input.substr(0, 400).c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  static const char* const kSources[] = {
      "filenames.txt",        "light_directions.txt", "light_intensities.txt",
      "normal.txt",           "material.json",        "scene.json",
      "capture.lp",           "lights.json",          "camera.json",
      "light_anisotropy.txt", "profile.icc"};
  static_assert(sizeof kSources / sizeof kSources[0] == kFuzzParsers);
  const int parser = data[0] % kFuzzParsers;
  const std::string source = kSources[parser];
  try {
    using namespace iphong::io;
    std::vector<std::string> warnings;
    switch (parser) {
      case 0:
        ParseFilenames(text, source, 1000);
        break;
      case 1:
        ParseLightDirections(text, source, 12, &warnings);
        break;
      case 2:
        ParseLightIntensities(text, source, 3);
        break;
      case 3:
        ParseNormalText(text, source, 4, 3);
        break;
      case 4:
        ParseMaterialJson(text, source);
        break;
      case 6:
      case 7:
        ParseLightFile(text, source, 0, &warnings, 1000);
        break;
      case 8:
        ParseCameraJson(text, source, &warnings);
        break;
      case 9:
        ParseScalars(text, source, 12);
        break;
      case 10: {
        const IccTransfer t =
            ReadIccTransfer(reinterpret_cast<const unsigned char*>(text.data()), text.size());
        if (t.found && t.statement.empty()) Finding("an ICC curve read without a statement", text);
        break;
      }
      default: {
        // No files are read from a fuzzed scene (base folder "": relative mesh paths do not
        // exist), and what the shapes would build is held to 64 MB.
        iphong::MemoryLimit memory;
        memory.bytes = 64u << 20;
        ParseScene(text, source, "/nonexistent-fuzz-base", memory);
      }
    }
    for (const std::string& w : warnings) {
      if (w.find('\n') != std::string::npos) Finding("multi-line warning: " + w, text);
    }
  } catch (const std::bad_alloc&) {
    Finding("std::bad_alloc: an allocation the input controls", text);
  } catch (const std::exception& e) {
    const std::string message = e.what();
    if (message.find('\n') != std::string::npos) Finding("multi-line message: " + message, text);
    if (message.rfind(source, 0) != 0) Finding("message does not name the file: " + message, text);
  }
  return 0;
}
