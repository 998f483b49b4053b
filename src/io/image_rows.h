// Images read and written a band of rows at a time, for captures and results larger than
// memory. Rows are 0 at the top, as everywhere (SPEC.md).
#pragma once

#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>

#include "core/types.h"
#include "io/image_io.h"

namespace iphong::io {

// Decodes rows of one image file, as displayed under an EXIF orientation (io/image_io.h); formats
// that only decode forward (PNG, JPEG) are reopened by OpenImageIO when a pass starts again at the
// top. Under a quarter turn (orientation 5–8) a displayed row is a stored column: each band then
// decodes the whole file, a slice of stored rows at a time (memory stays a band's; time grows
// with the number of bands).
class ImageRowReader {
 public:
  // Throws std::runtime_error naming the file when it is not an image.
  explicit ImageRowReader(const std::string& path, int orientation = kFileOrientation);
  const ImageHeader& header() const { return header_; }  // as displayed
  // Displayed rows [y0, y1) as float values, header().channels per pixel (integer formats scaled
  // to 0..1, as ReadImage). Throws std::runtime_error "PATH: cannot decode rows Y0..Y1-1: why".
  ImageF ReadRows(int y0, int y1);

 private:
  ImageF ReadStoredRows(int y0, int y1, int shown_y0, int shown_y1);  // stored rows [y0, y1)
  std::string path_;
  ImageHeader header_;
  int orientation_ = 1;                       // the one applied
  int stored_width_ = 0, stored_height_ = 0;  // the display window, before the orientation
  int data_x_ = 0, data_y_ = 0;  // the data window's origin in it (internal::DataPlacement)
  bool data_whole_ = true;
  std::unique_ptr<OIIO::ImageInput> in_;
};

// Writes an image band by band, top to bottom, straight to `path` (a new file in an output
// folder's staging area): every byte goes through checked writes and the file is synced and
// reread at Finish, so a full disk is an OutputError, never a short file that looks complete.
// Values are stored as WriteImage stores them (integer formats clamped or sRGB-encoded).
class ImageRowWriter {
 public:
  ImageRowWriter(const std::string& path, int width, int height, int channels,
                 const WriteOptions& options = {});
  ~ImageRowWriter();  // an unfinished file is removed
  ImageRowWriter(const ImageRowWriter&) = delete;
  ImageRowWriter& operator=(const ImageRowWriter&) = delete;
  // The next rows: band.width and band.channels as opened, rows continuing the last call's.
  void WriteRows(const ImageF& band);
  int rows_written() const { return next_row_; }
  void Finish();  // all rows written; throws OutputError when the file is not what was written

 private:
  class Proxy;
  std::string path_;
  int width_, height_, channels_;
  WriteOptions options_;
  bool is_float_ = false;
  int next_row_ = 0;
  bool finished_ = false;
  std::unique_ptr<Proxy> proxy_;
  std::unique_ptr<OIIO::ImageOutput> out_;
};

}  // namespace iphong::io
