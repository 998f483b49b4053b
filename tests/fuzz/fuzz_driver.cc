// A bounded, deterministic mutation fuzzer for fuzz_parsers.cc where libFuzzer is not available
// (GCC builds, CI): seeds from the fixtures, then N mutations of them — byte flips, insertions,
// deletions, duplicated spans and splices of tokens that broke parsers before (huge numbers,
// NaN, deep nesting, control bytes). Usage: fuzz_driver FIXTURES_DIR [ITERATIONS] [SEED], or
// fuzz_driver FIXTURES_DIR --seeds-to DIR to write the seeds as a libFuzzer corpus.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

#include "../io/icc_test_profiles.h"
#include "fuzz_parsers.h"

namespace {
namespace fs = std::filesystem;

std::string Read(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

std::vector<std::string> Seeds(const fs::path& fixtures) {
  std::vector<std::string> seeds;
  auto add = [&](int parser, const std::string& text) {
    seeds.push_back(std::string(1, static_cast<char>(parser)) + text);
  };
  std::string names, directions, intensities, normals;
  for (int i = 1; i <= 12; ++i) {
    names += (i < 10 ? "00" : "0") + std::to_string(i) + ".png\n";
    directions += "0." + std::to_string(i) + " -0.2 0.9\n";
  }
  intensities = "1 1 1\n0.5 0.6 0.7\r\n2e0 1 1\n";
  for (int i = 0; i < 12; ++i) normals += "0 0 1\n";
  add(0, names);
  add(1, directions);
  add(2, intensities);
  add(3, normals);
  add(4, R"({"model": "blinn-phong", "ambient": [1, 1, 1], "ka": 0.02, "ks": [0.35, 0.35, 0.3],
             "shininess": 24, "kd": [0.5, 0.5, 0.5]})");
  add(6, "3\nC:\\capture\\IMG 01.jpg 0 0 1\nIMG_02.jpg 0.6, 0, 0.8\nIMG_03.jpg 0 0.6 0.8\n");
  add(6, "12\n" + directions);
  add(7, R"({"lights": [{"lightId": 0, "type": "directional", "direction": [0, 0, -1],
             "intensity": [1, 2, 3]}, {"lightId": 1, "direction": [0.6, 0, -0.8], "intensity": 1},
             {"direction": [0, -0.6, -0.8]}]})");
  add(8, R"({"fx": 700, "fy": 700.5, "cx": 159.5, "cy": 127.5, "width": 320})");
  add(8, R"({"pixel_size": 0.25})");
  std::string anisotropy;
  for (int i = 0; i < 12; ++i) anisotropy += i % 3 ? "1\n" : "0.5\n";
  add(9, anisotropy);
  // ICC profiles of one red curve: a 'curv' gamma 2.2 and a 'para' (sRGB's parameters).
  add(10, iphong::io::icc_test::IccProfile(iphong::io::icc_test::Curv({563})));
  add(10, iphong::io::icc_test::IccProfile(
              iphong::io::icc_test::Para(3, {2.4, 1 / 1.055, 0.055 / 1.055, 1 / 12.92, 0.04045})));
  for (const char* folder : {"scenes", "bad/scenes"}) {
    for (const auto& entry : fs::directory_iterator(fixtures / folder)) {
      if (entry.path().extension() == ".json") add(5, Read(entry.path()));
    }
  }
  return seeds;
}

const char* const kTokens[] = {"1e400",
                               "-1e400",
                               "nan",
                               "inf",
                               "-0",
                               "4294967328",
                               "9223372036854775808",
                               "1e308",
                               "0x1p3",
                               "[",
                               "]",
                               "{",
                               "}",
                               "\"",
                               ",",
                               ":",
                               "\n",
                               "\r",
                               "\t",
                               "\\u0000",
                               "\\n",
                               "null",
                               "true",
                               "[[[[[[[[[[[[[[[[[[[[[[[[",
                               "\"count\": 100000",
                               "\"subdivisions\": 9",
                               "\"divisions\": 8192",
                               "\"resolution\": [65536, 65536]",
                               "\"fov_deg\": 180",
                               "\xff\xfe",
                               "\"shape\": \"mesh\", \"path\": \"/dev/zero\"",
                               "\"type\": \"ring\"",
                               "1e-320"};

std::string Mutate(std::string input, std::mt19937_64& rng) {
  auto pick = [&](std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng() % n); };
  const int edits = 1 + static_cast<int>(pick(4));
  for (int e = 0; e < edits; ++e) {
    const std::size_t at = 1 + pick(input.size());  // byte 0 chooses the parser
    switch (pick(6)) {
      case 0:
        if (at < input.size()) input[at] = static_cast<char>(input[at] ^ (1 << pick(8)));
        break;
      case 1:
        input.insert(std::min(at, input.size()), 1, static_cast<char>(pick(256)));
        break;
      case 2:
        if (at < input.size()) input.erase(at, 1 + pick(16));
        break;
      case 3: {
        const std::size_t from = 1 + pick(input.size()), length = pick(32);
        if (from < input.size()) {
          input.insert(std::min(at, input.size()), input.substr(from, length));
        }
        break;
      }
      default:
        input.insert(std::min(at, input.size()), kTokens[pick(std::size(kTokens))]);
    }
  }
  return input;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FIXTURES_DIR [ITERATIONS] [SEED]\n", argv[0]);
    return 2;
  }
  const std::vector<std::string> seeds = Seeds(argv[1]);
  if (argc == 4 && std::string(argv[2]) == "--seeds-to") {
    fs::create_directories(argv[3]);
    for (std::size_t i = 0; i < seeds.size(); ++i) {
      std::ofstream(fs::path(argv[3]) / ("seed-" + std::to_string(i)), std::ios::binary)
          << seeds[i];
    }
    return 0;
  }
  const long iterations = argc > 2 ? std::atol(argv[2]) : 20000;
  std::mt19937_64 rng(argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1);
  auto run = [](const std::string& input) {
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(input.data()), input.size());
  };
  for (const std::string& seed : seeds) run(seed);
  long per_parser[kFuzzParsers] = {};
  for (long i = 0; i < iterations; ++i) {
    std::string input = Mutate(seeds[rng() % seeds.size()], rng);
    if (rng() % 4 == 0) input = Mutate(input, rng);             // further from the seeds
    const int parser = static_cast<int>(rng() % kFuzzParsers);  // any parser, any text
    input[0] = static_cast<char>(parser);
    ++per_parser[parser];
    run(input);
  }
  // Every parser must have been fed mutations (a modulus smaller than the parsers' count once
  // left the .lp and AliceVision readers unfuzzed here).
  for (int p = 0; p < kFuzzParsers && iterations >= 100 * kFuzzParsers; ++p) {
    if (per_parser[p] < iterations / (4 * kFuzzParsers)) {
      std::fprintf(stderr, "fuzz_driver: parser %d got %ld of %ld mutations\n", p, per_parser[p],
                   iterations);
      return 1;
    }
  }
  std::printf("fuzz_driver: %zu seeds and %ld mutations, no finding\n", seeds.size(), iterations);
  return 0;
}
