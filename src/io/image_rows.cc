#include "io/image_rows.h"

#include <OpenImageIO/filesystem.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/errors.h"
#include "io/files.h"
#include "io/image_internal.h"

namespace iphong::io {

ImageRowReader::ImageRowReader(const std::string& path, int orientation) : path_(path) {
  ImageHeader file;
  in_ = internal::OpenImageChecked(path, &file);
  header_ = internal::Oriented(file, orientation);
  orientation_ = orientation == kFileOrientation ? file.orientation : orientation;
  const internal::DataPlacement place = internal::PlacementOf(*in_);
  stored_width_ = place.display_width;
  stored_height_ = place.display_height;
  data_x_ = place.x, data_y_ = place.y, data_whole_ = place.whole;
}

ImageF ImageRowReader::ReadStoredRows(int y0, int y1, int shown_y0, int shown_y1) {
  const OIIO::ImageSpec& spec = in_->spec();
  const int c = header_.channels;
  internal::DataPlacement place;
  place.display_width = stored_width_, place.display_height = stored_height_;
  place.x = data_x_, place.y = data_y_, place.whole = data_whole_;
  ImageF band(stored_width_, y1 - y0, c);
  // The data window's rows among display rows [y0, y1); the rest of the band stays black.
  const long long r0 = std::max<long long>(0, static_cast<long long>(y0) - place.y);
  const long long r1 = std::min<long long>(spec.height, static_cast<long long>(y1) - place.y);
  if (r1 <= r0) return band;
  const auto fail = [&] {
    throw std::runtime_error(path_ + ": cannot decode rows " + std::to_string(shown_y0) + ".." +
                             std::to_string(shown_y1 - 1) + ": " + OneLine(in_->geterror()));
  };
  // A tiled file is read by whole rows of tiles: OpenImageIO 2.4's read_scanlines divides by
  // zero on one (SIGFPE).
  int first = static_cast<int>(r0), last = static_cast<int>(r1);
  if (spec.tile_width > 0 && spec.tile_height > 0) {
    first = first / spec.tile_height * spec.tile_height;
    last = static_cast<int>(std::min<long long>(
        spec.height, (r1 + spec.tile_height - 1) / spec.tile_height * spec.tile_height));
  }
  const bool direct = place.whole && first == r0 && last == r1;
  std::vector<float> rows;
  if (!direct) rows.resize(std::size_t(spec.width) * (last - first) * c);
  float* to = direct ? band.pixels.data() : rows.data();
  const bool ok =
      spec.tile_width > 0 && spec.tile_height > 0
          ? in_->read_tiles(0, 0, spec.x, spec.x + spec.width, spec.y + first, spec.y + last,
                            spec.z, spec.z + std::max(1, spec.depth), header_.first_channel,
                            header_.first_channel + c, OIIO::TypeDesc::FLOAT, to)
          : in_->read_scanlines(0, 0, spec.y + first, spec.y + last, 0, header_.first_channel,
                                header_.first_channel + c, OIIO::TypeDesc::FLOAT, to);
  if (!ok) fail();
  if (!direct)
    internal::PlaceRows(rows.data(), spec.width, first, last - first, c, place, y0, band);
  return band;
}

ImageF ImageRowReader::ReadRows(int y0, int y1) {
  if (y0 < 0 || y1 > header_.height || y1 <= y0) {
    throw std::logic_error(path_ + ": rows " + std::to_string(y0) + ".." + std::to_string(y1) +
                           " outside the image");
  }
  const int c = header_.channels;
  if (orientation_ == 1) return ReadStoredRows(y0, y1, y0, y1);
  ImageF band(header_.width, y1 - y0, c);
  auto put = [&](const ImageF& stored, int stored_y0) {
    for (int y = y0; y < y1; ++y) {
      for (int x = 0; x < header_.width; ++x) {
        int sx, sy;
        internal::StoredPixel(orientation_, stored_width_, stored_height_, x, y, &sx, &sy);
        if (sy < stored_y0 || sy >= stored_y0 + stored.height) continue;
        const float* from =
            stored.pixels.data() + (std::size_t(sy - stored_y0) * stored.width + sx) * c;
        std::copy(from, from + c, band.pixels.data() + (std::size_t(y - y0) * band.width + x) * c);
      }
    }
  };
  if (!OrientationSwapsAxes(orientation_)) {
    // A mirror or half turn keeps rows rows: the same count of stored rows, maybe from the bottom.
    const bool flipped = orientation_ == 3 || orientation_ == 4;
    const int s0 = flipped ? stored_height_ - y1 : y0, s1 = flipped ? stored_height_ - y0 : y1;
    put(ReadStoredRows(s0, s1, y0, y1), s0);
    return band;
  }
  // A quarter turn: every stored row holds a piece of these displayed rows. Slices of stored rows
  // about as large as the band keep memory at twice the band's.
  const int slice =
      std::max<int>(1, static_cast<int>(std::min<double>(
                           stored_height_, double(y1 - y0) * header_.width / stored_width_)));
  for (int s0 = 0; s0 < stored_height_; s0 += slice) {
    put(ReadStoredRows(s0, std::min(stored_height_, s0 + slice), y0, y1), s0);
  }
  return band;
}

// OpenImageIO's writers do not all check what the file system says; this proxy does, with
// positioned writes (OpenEXR goes back to fill in its offset table), and remembers the first
// failure for Finish.
class ImageRowWriter::Proxy : public OIIO::Filesystem::IOProxy {
 public:
  explicit Proxy(const std::string& path) : IOProxy(path, Write) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ < 0) error_ = errno;
  }
  ~Proxy() override { close(); }
  const char* proxytype() const override { return "iphong-checked-file"; }
  void close() override {
    if (fd_ >= 0) {
      if (::close(fd_) != 0 && error_ == 0) error_ = errno;
      fd_ = -1;
    }
    m_mode = Closed;
  }
  size_t write(const void* buf, size_t size) override {
    const size_t n = pwrite(buf, size, m_pos);
    m_pos += static_cast<int64_t>(n);
    return n;
  }
  size_t pwrite(const void* buf, size_t size, int64_t offset) override {
    if (fd_ < 0 || error_ != 0) return 0;
    const char* bytes = static_cast<const char*>(buf);
    size_t done = 0;
    while (done < size) {
      const ssize_t n = ::pwrite(fd_, bytes + done, size - done, offset + done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        error_ = n < 0 ? errno : EIO;
        return done;
      }
      done += static_cast<size_t>(n);
    }
    end_ = std::max<int64_t>(end_, offset + static_cast<int64_t>(size));
    return size;
  }
  size_t size() const override { return static_cast<size_t>(end_); }
  // Delayed allocation and network file systems report a full disk only at the sync.
  int Sync() {
    if (fd_ >= 0 && error_ == 0 && ::fsync(fd_) != 0) error_ = errno;
    struct stat st {};
    if (fd_ >= 0 && error_ == 0 && (::fstat(fd_, &st) != 0 || st.st_size != end_)) error_ = EIO;
    close();
    return error_;
  }
  int error() const { return error_; }

 private:
  int fd_ = -1;
  int error_ = 0;
  int64_t end_ = 0;
};

ImageRowWriter::ImageRowWriter(const std::string& path, int width, int height, int channels,
                               const WriteOptions& options)
    : path_(path), width_(width), height_(height), channels_(channels), options_(options) {
  if (width < 1 || height < 1 || channels < 1) {
    throw std::logic_error(path + ": refusing to write an empty image");
  }
  is_float_ = internal::IsFloatImagePath(path);
  if (!is_float_ && options.bits != 8 && options.bits != 16) {
    throw std::logic_error(path + ": integer images are 8 or 16 bits per channel");
  }
  const OIIO::TypeDesc format =
      is_float_ ? OIIO::TypeDesc::FLOAT
                : (options.bits == 16 ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8);
  OIIO::ImageSpec spec(width, height, channels, format);
  if (is_float_ || options.encoding != Encoding::kData) {
    spec.attribute("oiio:ColorSpace",
                   is_float_ || options.encoding == Encoding::kLinear ? "Linear" : "sRGB");
  }
  spec.attribute("Software", "iphong");
  spec.attribute("oiio:UnassociatedAlpha", 1);  // a fourth channel as given, as WriteImage does
  proxy_ = std::make_unique<Proxy>(path);
  if (proxy_->error() != 0) throw OutputError(path + ": " + std::strerror(proxy_->error()));
  out_ = OIIO::ImageOutput::create(path);
  if (!out_) throw OutputError(path + ": no image writer for this format");
  if (!out_->set_ioproxy(proxy_.get()) || !out_->open(path, spec)) {
    throw OutputError(path + ": cannot start writing: " + OneLine(out_->geterror()));
  }
}

ImageRowWriter::~ImageRowWriter() {
  if (finished_) return;
  out_.reset();
  proxy_.reset();
  ::unlink(path_.c_str());
}

void ImageRowWriter::WriteRows(const ImageF& band) {
  if (band.width != width_ || band.channels != channels_ || band.height < 1 ||
      next_row_ + band.height > height_) {
    throw std::logic_error(path_ + ": a band that does not continue the image");
  }
  std::vector<float> pixels = band.pixels;
  if (!is_float_) {
    for (float& v : pixels) {
      if (!std::isfinite(v)) v = 0.0f;
      v = options_.encoding == Encoding::kSrgb ? LinearToSrgb(v) : std::clamp(v, 0.0f, 1.0f);
    }
  }
  if (!out_->write_scanlines(next_row_, next_row_ + band.height, 0, OIIO::TypeDesc::FLOAT,
                             pixels.data()) ||
      proxy_->error() != 0) {
    throw OutputError(path_ + ": cannot write rows " + std::to_string(next_row_) + "..: " +
                      (proxy_->error() != 0 ? std::string(std::strerror(proxy_->error()))
                                            : OneLine(out_->geterror())));
  }
  next_row_ += band.height;
}

void ImageRowWriter::Finish() {
  if (next_row_ != height_) {
    throw std::logic_error(path_ + ": finished after " + std::to_string(next_row_) + " of " +
                           std::to_string(height_) + " rows");
  }
  const bool closed = out_->close();
  const std::string why = OneLine(out_->geterror());
  out_.reset();
  if (const int error = proxy_->Sync(); error != 0) {
    throw OutputError(path_ + ": " + std::strerror(error));
  }
  if (!closed) throw OutputError(path_ + ": cannot finish: " + why);
  // Reread: the header must state what was written.
  ImageHeader header;
  internal::OpenImageChecked(path_, &header);
  if (header.width != width_ || header.height != height_ || header.channels != channels_) {
    throw OutputError(path_ + ": reads back as " + SizeText(header.width, header.height));
  }
  finished_ = true;
}

}  // namespace iphong::io
