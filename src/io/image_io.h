// Reading and writing images with OpenImageIO. The only place pixels touch the disk.
//
// In memory images are linear float (core/types.h). 8/16-bit files are written clamped to [0, 1],
// optionally sRGB-encoded; float files (EXR, float TIFF) keep the values as they are.
#pragma once

#include <functional>
#include <string>

#include "core/resources.h"
#include "core/types.h"

namespace iphong::io {

enum class Encoding {
  kLinear,  // values written as they are (scaled to the integer range for 8/16-bit)
  kSrgb,    // sRGB transfer curve applied before quantizing (8/16-bit only)
  // Values written as they are with no colour-space statement: pictures of data (normal maps),
  // which a gAMA 1.0 tag made browsers show washed out.
  kData,
};

struct WriteOptions {
  // Bits per channel for integer formats: 8 or 16. Ignored by float formats (.exr, .hdr).
  int bits = 8;
  Encoding encoding = Encoding::kSrgb;
};

// Encodes the image in memory (the format from the extension), then writes it as a new file with
// io/files.h's verified write. Outputs go through an OutputFolder, which picks `path`. Throws
// OutputError naming the file.
void WriteImage(const std::string& path, const ImageF& image, const WriteOptions& options = {});

// EXIF orientation (TIFF tag 274, JPEG Exif): how a viewer turns or mirrors the stored pixels
// to display them. 1 = as stored; 2 mirrored left-right; 3 turned 180°; 4 mirrored top-bottom;
// 5 transposed; 6 turned 90° clockwise; 7 transverse; 8 turned 90° counter-clockwise. iphong reads
// images as they are displayed (a mask drawn on the displayed photo fits it), so rows and columns
// everywhere are displayed ones.
constexpr int kFileOrientation = 0;  // "the orientation the file states"
// True for 5–8, where the displayed width is the stored height.
bool OrientationSwapsAxes(int orientation);
// "turned 90° clockwise", "mirrored left-right", ...; "as stored" for 1.
std::string DescribeOrientation(int orientation);

struct ImageHeader {
  // As displayed (after the orientation); the channels read: an EXR of several layers (a
  // renderer's passes) is read as its colour layer (internal::ColourLayer), from first_channel.
  int width = 0, height = 0, channels = 0;
  int first_channel = 0;
  std::string layer;       // that layer's name ("" when the file has one layer)
  int orientation = 1;     // as the file states it (1 when it states none)
  bool is_float = false;   // half or float samples: no code value clips at 1
  int alpha_channel = -1;  // the channel the file names alpha, −1: none
  bool lossy = false;      // a lossy format (JPEG, WebP, HEIF): values are blurred
};

// The size a file declares, read from its header only. Refuses what is not a regular file, a
// header no reader accepts, and sizes iphong cannot hold: more than 2^31 pixels, or a declared size
// the file is far too small to contain (a 200-byte PNG that says 100000×100000: no decoder
// compresses that well; a truncated or forged file). Throws std::runtime_error naming the file.
ImageHeader ReadImageHeader(const std::string& path);

// Reads any format OpenImageIO knows into linear float, integer formats scaled to [0, 1]
// (no transfer curve is undone), turned as displayed: by `orientation` (1–8), or by the one the
// file states (kFileOrientation). Checks the header first (ReadImageHeader); then `check`, when
// given, sees it (its size as displayed under the orientation applied) and may throw (a size that
// is not the dataset's, a mesh budget); then the memory the decoded image needs is checked against
// `memory` (ResourceError). Nothing is allocated before. Throws std::runtime_error naming the file.
ImageF ReadImage(const std::string& path, const MemoryLimit& memory = {},
                 const std::function<void(const ImageHeader&)>& check = {},
                 int orientation = kFileOrientation);

// How a file stores its values, and what it states about their encoding. Formats that state one:
// any file with an ICC profile whose curve is linear or a display gamma (io/icc_profile.h; first,
// as the profile is what colour-managed software reads), JPEG (display-encoded, sRGB, by the
// format's own convention), PNG with an sRGB, iCCP (a profile without such a curve) or gAMA
// chunk, any file with an Exif ColorSpace tag of sRGB, and camera raw (developed linear: every
// reader here asks LibRaw for linear values and the camera's fixed daylight white balance).
// OpenImageIO reports "sRGB" for every PNG, chunk or not, so PNG chunks are read here from the file
// itself.
struct StoredEncoding {
  ImageHeader header;   // size and sample type as declared (ReadImageHeader's checks)
  int bits = 8;         // per channel as stored
  std::string format;   // OpenImageIO's name: "png", "jpeg", "targa", "openexr", ...
  bool stated = false;  // the file states its encoding ...
  Encoding encoding = Encoding::kLinear;  // ... as this
  std::string statement;  // how: "sRGB chunk", "gAMA 0.45455", "JPEG", "Exif ColorSpace sRGB"
};
StoredEncoding ReadStoredEncoding(const std::string& path);

// A mask picture: a pixel is inside where any of its colour channels (the first three that are
// not alpha) is non-zero. Two exceptions, each said in `how` ("" otherwise):
// - an alpha channel that is not the same everywhere marks the object instead (a cut-out, whose
//   transparent background may keep any colour): inside where alpha is non-zero;
// - a lossy format (JPEG, WebP, HEIF) leaves faint non-zero values around the object, so a pixel
//   is inside where it is above half the picture's largest value.
Mask ReadMask(const std::string& path, const MemoryLimit& memory = {}, std::string* how = nullptr);

// The sRGB transfer curve and its inverse, on [0, 1].
float LinearToSrgb(float linear);
float SrgbToLinear(float encoded);
// SrgbToLinear for a value in double (solve::CompareReadings' re-reading).
double DecodeSrgb(double encoded);

// SrgbToLinear over a whole image. Values that are 16-bit codes (k/65535, which 8-bit codes k/255
// also are) go through a table of the 65536 exact results, one lookup instead of a pow each;
// anything else is computed.
void LinearizeSrgb(ImageF& image);

}  // namespace iphong::io
