// What the safe output costs: a dataset of per-light images written through an OutputFolder
// (encoded in memory, written, fsync'ed, size-checked, committed by one rename) against the same
// images written straight to their paths by OpenImageIO (the baseline, no verification), and the
// commit of an earlier output replaced in place under a journal.
#include <benchmark/benchmark.h>

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <string>

#include "io/image_io.h"
#include "io/output_folder.h"

namespace {
namespace fs = std::filesystem;
using iphong::ImageF;

constexpr int kImages = 24;

ImageF Gradient(int size) {
  ImageF image(size, size, 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    image.pixels[i] = static_cast<float>((i * 2654435761u) % 65536) / 65536.0f;
  }
  return image;
}

std::string Name(int j) { return std::to_string(1000 + j).substr(1) + ".png"; }

fs::path Scratch() {
  const fs::path dir = fs::temp_directory_path() / "iphong-bench-io";
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Baseline: OpenImageIO writes each image to its final path; nothing checks or flushes it.
void BM_PlainOiioWrites(benchmark::State& state) {
  const ImageF image = Gradient(static_cast<int>(state.range(0)));
  const fs::path dir = Scratch();
  int run = 0;
  for (auto _ : state) {
    const fs::path out = dir / std::to_string(run++);
    fs::create_directories(out);
    for (int j = 0; j < kImages; ++j) {
      const std::string path = (out / Name(j)).string();
      auto writer = OIIO::ImageOutput::create(path);
      OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::UINT16);
      writer->open(path, spec);
      writer->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
      writer->close();
    }
  }
  state.SetItemsProcessed(state.iterations() * kImages);
  fs::remove_all(dir);
}

// iphong: the same images through an OutputFolder into a new folder.
void BM_OutputFolderNew(benchmark::State& state) {
  const ImageF image = Gradient(static_cast<int>(state.range(0)));
  const fs::path dir = Scratch();
  int run = 0;
  for (auto _ : state) {
    iphong::io::OutputFolderOptions options;
    options.command = "bench";
    iphong::io::OutputFolder out((dir / std::to_string(run++)).string(), options);
    for (int j = 0; j < kImages; ++j) {
      iphong::io::WriteImage(out.file(Name(j)), image, {16, iphong::io::Encoding::kLinear});
    }
    out.Commit();
  }
  state.SetItemsProcessed(state.iterations() * kImages);
  fs::remove_all(dir);
}

// iphong: replacing an earlier output in place (--overwrite): staging inside, journal, renames.
void BM_OutputFolderOverwrite(benchmark::State& state) {
  const ImageF image = Gradient(static_cast<int>(state.range(0)));
  const fs::path dir = Scratch();
  iphong::io::OutputFolderOptions options;
  options.command = "bench";
  options.overwrite = true;
  for (auto _ : state) {
    iphong::io::OutputFolder out((dir / "out").string(), options);
    for (int j = 0; j < kImages; ++j) {
      iphong::io::WriteImage(out.file(Name(j)), image, {16, iphong::io::Encoding::kLinear});
    }
    out.Commit();
  }
  state.SetItemsProcessed(state.iterations() * kImages);
  fs::remove_all(dir);
}

}  // namespace

BENCHMARK(BM_PlainOiioWrites)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OutputFolderNew)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OutputFolderOverwrite)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
