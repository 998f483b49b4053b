#include "io/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "core/errors.h"
#include "io/files.h"
#include "io/image_internal.h"

namespace iphong::io {
namespace fs = std::filesystem;

namespace {

bool IsFloatFormat(const fs::path& path) {
  const std::string ext = LowerExtension(path.string());
  return ext == ".exr" || ext == ".hdr" || ext == ".pfm";
}

[[noreturn]] void Fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + OneLine(what));
}

// Deflate, the best general-purpose coder in these formats, stops near 1032:1; a file that
// claims far more raw data per stored byte than that cannot hold its pixels.
constexpr double kMaxCompression = 4096;
// Below this declared size the check is pointless: decoding a small lie costs nothing.
constexpr double kPlausibilityFloor = 64e6;
constexpr double kMaxPixels = 2147483647.0;

std::unique_ptr<OIIO::ImageInput> OpenChecked(const std::string& path, ImageHeader* header) {
  const std::uint64_t file_bytes = RequireRegularFile(path);
  // Camera raw files are developed by LibRaw, which OpenImageIO asks by default for the sRGB curve
  // and each shot's own white balance: photometric stereo needs the sensor's linear values, with
  // one set of channel gains for every photo of a capture (the camera's daylight multipliers).
  OIIO::ImageSpec config;
  config.attribute("raw:ColorSpace", "linear");
  config.attribute("raw:use_camera_wb", 0);
  // A PNG's (or TIFF's) unassociated alpha is left as stored: OpenImageIO would otherwise multiply
  // the colour by it, and a photo would read darker wherever it is partly transparent.
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) {
    std::string why = OIIO::geterror();
    Fail(path, why.empty() ? "cannot open as an image" : why);
  }
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1) {
    Fail(path, "empty or not a 2D image");
  }
  const internal::DataPlacement place = internal::PlacementOf(*in);
  const double pixels = static_cast<double>(spec.width) * spec.height;
  const double shown = static_cast<double>(place.display_width) * place.display_height;
  const int bits =
      spec.get_int_attribute("oiio:BitsPerSample", static_cast<int>(spec.format.size()) * 8);
  const double declared = pixels * spec.nchannels * std::max(bits, 1) / 8.0;
  if (declared > kPlausibilityFloor && declared > kMaxCompression * file_bytes) {
    Fail(path, "declares " + SizeText(spec.width, spec.height) + " pixels but has only " +
                   std::to_string(file_bytes) + " bytes: truncated or corrupt");
  }
  if (pixels > kMaxPixels || spec.nchannels > 64) {
    Fail(path, "declares " + SizeText(spec.width, spec.height) + "x" +
                   std::to_string(spec.nchannels) +
                   ", more than iphong handles (2^31 pixels, 64 channels)");
  }
  if (shown > kMaxPixels) {
    Fail(path, "declares a display window of " +
                   SizeText(place.display_width, place.display_height) +
                   " pixels, more than iphong handles (2^31)");
  }
  int orientation = spec.get_int_attribute("Orientation", 1);
  if (orientation < 1 || orientation > 8) orientation = 1;  // what viewers do with a bad tag
  const std::string format = in->format_name();
  int first = 0, count = spec.nchannels;
  std::string layer;
  internal::ColourLayer(path, spec, &first, &count, &layer);
  const int alpha = spec.alpha_channel - first;
  *header = {place.display_width,
             place.display_height,
             count,
             first,
             layer,
             orientation,
             spec.format.is_floating_point(),
             alpha >= 0 && alpha < count ? alpha : -1,
             format == "jpeg" || format == "webp" || format == "heif"};
  if (OrientationSwapsAxes(orientation)) std::swap(header->width, header->height);
  return in;
}

}  // namespace

namespace internal {

void ColourLayer(const std::string& path, const OIIO::ImageSpec& spec, int* first, int* count,
                 std::string* layer) {
  *first = 0, *count = spec.nchannels, layer->clear();
  const int n = std::min<int>(spec.nchannels, static_cast<int>(spec.channelnames.size()));
  const auto split = [](const std::string& name) {
    const auto dot = name.rfind('.');
    return dot == std::string::npos ? std::pair<std::string, std::string>{"", name}
                                    : std::pair{name.substr(0, dot), name.substr(dot + 1)};
  };
  std::vector<std::string> layers;  // in file order, each once
  for (int c = 0; c < n; ++c) {
    const std::string l = split(spec.channelnames[c]).first;
    if (std::find(layers.begin(), layers.end(), l) == layers.end()) layers.push_back(l);
  }
  if (layers.size() < 2) return;
  // A layer's R, G, B in a row (OpenImageIO lists each layer's channels together, R G B A first).
  const auto colour_at = [&](const std::string& l) {
    for (int c = 0; c + 2 < n; ++c) {
      if (spec.channelnames[c] == (l.empty() ? "" : l + ".") + "R" &&
          spec.channelnames[c + 1] == (l.empty() ? "" : l + ".") + "G" &&
          spec.channelnames[c + 2] == (l.empty() ? "" : l + ".") + "B") {
        return c;
      }
    }
    return -1;
  };
  std::vector<std::string> colour;
  for (const std::string& l : layers) {
    if (colour_at(l) >= 0) colour.push_back(l);
  }
  if (colour.empty()) return;
  std::string chosen;
  if (std::find(colour.begin(), colour.end(), "") != colour.end()) {
    chosen = "";
  } else if (colour.size() == 1) {
    chosen = colour[0];
  } else {
    std::vector<std::string> beauty;
    for (const std::string& l : colour) {
      std::string last = split(l).second;
      for (char& ch : last) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      if (last == "combined" || last == "beauty" || last == "rgba" || last == "color") {
        beauty.push_back(l);
      }
    }
    if (beauty.size() != 1) {
      std::string names;
      for (const std::string& l : colour) names += (names.empty() ? "" : ", ") + l;
      throw std::runtime_error(path + ": holds " + std::to_string(colour.size()) +
                               " colour layers (" + names +
                               ") and none is the picture (Combined, beauty, rgba or color): "
                               "save the image pass alone, or name it so");
    }
    chosen = beauty[0];
  }
  *first = colour_at(chosen);
  const std::string a = (chosen.empty() ? "" : chosen + ".") + "A";
  *count = *first + 3 < n && spec.channelnames[*first + 3] == a ? 4 : 3;
  *layer = chosen;
}

DataPlacement PlacementOf(OIIO::ImageInput& in) {
  const OIIO::ImageSpec& spec = in.spec();
  DataPlacement p;
  p.display_width = spec.width;
  p.display_height = spec.height;
  if (std::string(in.format_name()) != "openexr" || spec.full_width <= 0 || spec.full_height <= 0) {
    return p;
  }
  p.display_width = spec.full_width;
  p.display_height = spec.full_height;
  // As wide integers: a forged header's origins may lie anywhere in int's range.
  const long long x = static_cast<long long>(spec.x) - spec.full_x;
  const long long y = static_cast<long long>(spec.y) - spec.full_y;
  const auto clamp = [](long long v) {
    return static_cast<int>(std::clamp<long long>(v, -(1LL << 30), 1LL << 30));
  };
  p.x = clamp(x), p.y = clamp(y);
  p.whole =
      p.x == 0 && p.y == 0 && spec.width == p.display_width && spec.height == p.display_height;
  return p;
}

void PlaceRows(const float* data, int data_width, int data_y0, int rows, int channels,
               const DataPlacement& place, int band_y0, ImageF& band) {
  const long long x0 = std::max<long long>(0, place.x);
  const long long x1 =
      std::min<long long>(band.width, static_cast<long long>(place.x) + data_width);
  if (x1 <= x0) return;
  for (int r = 0; r < rows; ++r) {
    const long long y = static_cast<long long>(place.y) + data_y0 + r - band_y0;
    if (y < 0 || y >= band.height) continue;
    const float* from = data + (std::size_t(r) * data_width + (x0 - place.x)) * channels;
    std::copy(from, from + (x1 - x0) * channels,
              band.at(static_cast<int>(x0), static_cast<int>(y)));
  }
}

std::unique_ptr<OIIO::ImageInput> OpenImageChecked(const std::string& path, ImageHeader* header) {
  return OpenChecked(path, header);
}

bool IsFloatImagePath(const std::string& path) { return IsFloatFormat(path); }

ImageHeader Oriented(const ImageHeader& file_header, int orientation) {
  if (orientation < 0 || orientation > 8) {
    throw std::logic_error("EXIF orientation " + std::to_string(orientation) + " is not 0-8");
  }
  if (orientation == kFileOrientation) return file_header;
  ImageHeader h = file_header;
  if (OrientationSwapsAxes(file_header.orientation) != OrientationSwapsAxes(orientation)) {
    std::swap(h.width, h.height);
  }
  return h;
}

ImageF Reorient(const ImageF& stored, int orientation) {
  if (orientation == 1) return stored;
  const bool swap = OrientationSwapsAxes(orientation);
  ImageF shown(swap ? stored.height : stored.width, swap ? stored.width : stored.height,
               stored.channels);
  const int c = stored.channels;
  for (int y = 0; y < shown.height; ++y) {
    for (int x = 0; x < shown.width; ++x) {
      int sx, sy;
      StoredPixel(orientation, stored.width, stored.height, x, y, &sx, &sy);
      const float* from = stored.pixels.data() + (std::size_t(sy) * stored.width + sx) * c;
      std::copy(from, from + c, shown.pixels.data() + (std::size_t(y) * shown.width + x) * c);
    }
  }
  return shown;
}

}  // namespace internal

bool OrientationSwapsAxes(int orientation) { return orientation >= 5 && orientation <= 8; }

std::string DescribeOrientation(int orientation) {
  switch (orientation) {
    case 2:
      return "mirrored left-right";
    case 3:
      return "turned 180°";
    case 4:
      return "mirrored top-bottom";
    case 5:
      return "transposed (mirrored and turned)";
    case 6:
      return "turned 90° clockwise";
    case 7:
      return "transversed (mirrored and turned)";
    case 8:
      return "turned 90° counter-clockwise";
    default:
      return "as stored";
  }
}

void WriteImage(const std::string& path, const ImageF& image, const WriteOptions& options) {
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0 ||
      image.pixels.size() != image.pixel_count() * image.channels) {
    throw std::logic_error(path + ": refusing to write an empty or inconsistent image");
  }
  const fs::path target(path);
  const bool is_float = IsFloatFormat(target);
  if (!is_float && options.bits != 8 && options.bits != 16) {
    throw std::logic_error(path + ": integer images are 8 or 16 bits per channel");
  }

  std::vector<float> pixels = image.pixels;
  if (!is_float) {
    for (float& v : pixels) {
      if (!std::isfinite(v)) v = 0.0f;
      v = options.encoding == Encoding::kSrgb ? LinearToSrgb(v) : std::clamp(v, 0.0f, 1.0f);
    }
  }

  const OIIO::TypeDesc format =
      is_float ? OIIO::TypeDesc::FLOAT
               : (options.bits == 16 ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8);
  OIIO::ImageSpec spec(image.width, image.height, image.channels, format);
  if (is_float || options.encoding != Encoding::kData) {
    spec.attribute("oiio:ColorSpace",
                   is_float || options.encoding == Encoding::kLinear ? "Linear" : "sRGB");
  }
  spec.attribute("Software", "iphong");
  // A fourth channel is written as given, as the readers above read it (no division by alpha).
  spec.attribute("oiio:UnassociatedAlpha", 1);

  // Encoded in memory, so the bytes reach the disk through one verified write: OpenImageIO's
  // writers can report success on a full disk.
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput memory(bytes);
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw OutputError(path + ": no image writer for this format");
  if (!out->set_ioproxy(&memory) || !out->open(path, spec) ||
      !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) || !out->close() || bytes.empty()) {
    throw OutputError(path + ": cannot encode: " + OneLine(out->geterror()));
  }
  out.reset();
  WriteFileVerified(path,
                    std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

ImageHeader ReadImageHeader(const std::string& path) {
  ImageHeader header;
  OpenChecked(path, &header);
  return header;
}

ImageF ReadImage(const std::string& path, const MemoryLimit& memory,
                 const std::function<void(const ImageHeader&)>& check, int orientation) {
  ImageHeader file;
  auto in = OpenChecked(path, &file);
  const ImageHeader h = internal::Oriented(file, orientation);
  if (check) check(h);
  const int turn = orientation == kFileOrientation ? file.orientation : orientation;
  const OIIO::ImageSpec& spec = in->spec();
  const internal::DataPlacement place = internal::PlacementOf(*in);
  // The float image, and the decoder's own buffer (or the turned copy) of at most the same size;
  // a data window other than the display window is decoded first, then placed.
  const double placed = place.whole ? 0.0 : static_cast<double>(spec.width) * spec.height;
  RequireMemory(memory, (2.0 * h.width * h.height + placed) * h.channels * sizeof(float),
                path + ": decoding this " + SizeText(h.width, h.height) + " image");
  ImageF image(place.display_width, place.display_height, h.channels);
  ImageF data;
  if (!place.whole) data = ImageF(spec.width, spec.height, h.channels);
  if (!in->read_image(0, 0, file.first_channel, file.first_channel + h.channels,
                      OIIO::TypeDesc::FLOAT, (place.whole ? image : data).pixels.data())) {
    Fail(path, "cannot decode: " + in->geterror());
  }
  in->close();
  if (!place.whole) {
    internal::PlaceRows(data.pixels.data(), data.width, 0, data.height, h.channels, place, 0,
                        image);
  }
  return turn == 1 ? image : internal::Reorient(image, turn);
}

Mask ReadMask(const std::string& path, const MemoryLimit& memory, std::string* how) {
  ImageHeader header;
  const ImageF m = ReadImage(path, memory, [&](const ImageHeader& h) { header = h; });
  const std::size_t n = m.pixel_count();
  const int alpha = header.alpha_channel;
  std::vector<int> channels;
  bool alpha_varies = false;
  if (alpha >= 0) {
    for (std::size_t p = 1; p < n && !alpha_varies; ++p) {
      alpha_varies = m.pixels[p * m.channels + alpha] != m.pixels[alpha];
    }
  }
  if (alpha_varies) {
    channels = {alpha};
  } else {
    for (int c = 0; c < m.channels && channels.size() < 3; ++c) {
      if (c != alpha) channels.push_back(c);
    }
  }
  float threshold = 0;
  if (header.lossy) {
    float largest = 0;
    for (std::size_t p = 0; p < n; ++p) {
      for (const int c : channels) largest = std::max(largest, m.pixels[p * m.channels + c]);
    }
    threshold = 0.5f * largest;
  }
  Mask mask(m.width, m.height, false);
  for (std::size_t p = 0; p < n; ++p) {
    for (const int c : channels) {
      if (m.pixels[p * m.channels + c] > threshold) mask.inside[p] = 1;
    }
  }
  if (how) {
    how->clear();
    if (alpha_varies) *how = "its alpha channel: transparent = background";
    if (header.lossy) {
      *how += std::string(how->empty() ? "" : "; ") +
              "above half its largest value: lossy compression leaves faint values around the "
              "object";
    }
  }
  return mask;
}

}  // namespace iphong::io
