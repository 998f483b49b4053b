#include "io/capture_bands.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "core/image_ops.h"
#include "core/parallel.h"
#include "io/dataset_internal.h"

namespace iphong::io {

struct CaptureBands::State {
  internal::Prepared p;
  DatasetLoadOptions options;
  std::vector<std::unique_ptr<ImageRowReader>> readers;  // opened by the first ReadBand
};

CaptureBands::CaptureBands(const std::string& directory, const DatasetLoadOptions& options)
    : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.options = options;
  s.options.load_images = false;
  s.options.load_ground_truth = false;
  s.p = internal::Prepare(directory, s.options);
}

// Every file's header, before the first band: a missing or wrong-sized image fails before any
// band is decoded. Not in the constructor, so a capture that turns out to fit in memory (and is
// read by LoadObservations) does not open its K files twice.
void CaptureBands::OpenReaders() {
  State& s = *state_;
  if (!s.readers.empty()) return;
  const Dataset& d = s.p.d;
  // The file that set the size, named as LoadObservations names it.
  const std::string reference = d.files.mask_path.empty()
                                    ? d.filenames[0]
                                    : std::filesystem::path(d.files.mask_path).filename().string();
  for (std::size_t j = 0; j < d.files.paths.size(); ++j) {
    const std::string& path = d.files.paths[j];
    auto reader = std::make_unique<ImageRowReader>(path, d.orientation);
    const ImageHeader& h = reader->header();
    s.p.d.image_counts[j].orientation = h.orientation;
    s.p.d.image_counts[j].integer_codes = !h.is_float;
    if (h.width != d.file_width || h.height != d.file_height) {
      throw std::runtime_error(path + ": is " + SizeText(h.width, h.height) + ", but " + reference +
                               " is " + SizeText(d.file_width, d.file_height));
    }
    s.readers.push_back(std::move(reader));
  }
}

CaptureBands::~CaptureBands() = default;

const Dataset& CaptureBands::dataset() const { return state_->p.d; }
int CaptureBands::width() const { return state_->p.d.mask.width; }
int CaptureBands::height() const { return state_->p.d.mask.height; }

double CaptureBands::BytesPerRow() const {
  const State& s = *state_;
  const Dataset& d = s.p.d;
  const double k = static_cast<double>(d.filenames.size());
  const int scale = s.options.capture.downscale;
  const double threads = std::min<double>(ResolveThreads(s.options.threads), k);
  // The observations (K × 3 floats a pixel), and per decoding thread the file rows behind one
  // working row: decoded, as RGB and cropped (three copies at most), then downscaled.
  // Four channels at most are decoded (RGBA; more are read as they come, rarely).
  return sizeof(float) * (k * 3 * width() + threads * scale * d.file_width * (4 + 6.0));
}

double CaptureBands::FixedBytes() const {
  const Dataset& d = state_->p.d;
  // The working mask and the cropped file mask, one byte a pixel, and each decoder's state.
  return static_cast<double>(d.mask.inside.size() + state_->p.file_mask.inside.size()) +
         d.filenames.size() * 128.0 * 1024;
}

solve::PhotometricData CaptureBands::ReadBand(int y0, int y1, bool count) {
  State& s = *state_;
  OpenReaders();
  Dataset& d = s.p.d;
  const int w = width(), scale = s.options.capture.downscale;
  if (y0 < 0 || y1 > height() || y1 <= y0) throw std::logic_error("band outside the capture");
  Mask band_mask(w, y1 - y0, false);
  std::copy(d.mask.inside.begin() + static_cast<std::ptrdiff_t>(y0) * w,
            d.mask.inside.begin() + static_cast<std::ptrdiff_t>(y1) * w, band_mask.inside.begin());
  solve::PhotometricData data =
      solve::ObservationLayout(w, y1 - y0, band_mask, d.light_directions, d.light_intensities);
  // Rows of the cropped file image behind the band (the crop's rows start at crop.y).
  const PixelRect& crop = s.p.crop;
  const int file_y0 = y0 * scale, file_rows = (y1 - y0) * scale;
  const int offset_y = crop.width > 0 ? crop.y : 0;
  const std::size_t k = s.readers.size();
  std::vector<std::string> errors(k);
  ParallelFor(0, k, 1, s.options.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t j = b; j < e; ++j) {
      try {
        const ImageF band = internal::WorkingRows(
            s.p, s.readers[j]->ReadRows(offset_y + file_y0, offset_y + file_y0 + file_rows), 0,
            file_rows, file_y0, scale, count ? &d.image_counts[j] : nullptr, d.files.paths[j]);
        if (auto m = solve::GatherImage(data, static_cast<int>(j), band.pixels.data());
            !m.empty()) {
          errors[j] = d.files.paths[j] + ": rows " + std::to_string(offset_y + file_y0) + ".." +
                      std::to_string(offset_y + file_y0 + file_rows - 1) + " " + m;
        }
      } catch (const std::exception& ex) {
        errors[j] = ex.what();
      }
    }
  });
  for (const std::string& error : errors)
    if (!error.empty()) throw std::runtime_error(error);
  return data;
}

}  // namespace iphong::io
