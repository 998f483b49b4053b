#include "io/normal_mat.h"

#include <fcntl.h>
#include <matio.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "core/errors.h"
#include "io/files.h"

namespace iphong::io {
namespace {

// A MAT-file (level 5) is a 128-byte header and then data elements, each an 8-byte tag (type,
// byte count) and its bytes. matio reads a cut-off compressed element as zeros without a word, so
// the elements are walked first: one that runs past the end of the file is an error.
void CheckMat5Complete(const std::string& path) {
  const std::uint64_t file_size = RequireRegularFile(path);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) FailInput(path, std::string("cannot open: ") + std::strerror(errno));
  struct Close {
    int fd;
    ~Close() { ::close(fd); }
  } closer{fd};
  char header[128];
  if (file_size < 128 || ::pread(fd, header, 128, 0) != 128) {
    FailInput(path, "too short for a MATLAB file (truncated?)");
  }
  if (std::string(header, 10) == "MATLAB 7.3") return;         // HDF5: its own checks apply
  const bool swap = header[126] == 'M' && header[127] == 'I';  // written big-endian
  auto word = [&](const unsigned char* b) {
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= static_cast<std::uint32_t>(b[swap ? 3 - k : k]) << (8 * k);
    return v;
  };
  for (std::uint64_t at = 128; at < file_size;) {
    unsigned char tag[8];
    if (at + 8 > file_size || ::pread(fd, tag, 8, static_cast<off_t>(at)) != 8) {
      FailInput(path, "ends inside a data element: truncated");
    }
    const std::uint32_t type = word(tag), count = word(tag + 4);
    if (type >> 16 != 0) {  // small data element: type and count in one word, 4 bytes of data
      at += 8;
      continue;
    }
    // Uncompressed elements are padded to 8 bytes (the file's last one may end unpadded).
    const std::uint64_t size = count;
    if (at + 8 + size > file_size) {
      FailInput(path, "a data element runs past the end of the file: truncated");
    }
    at += 8 + (type == 15 ? size : (size + 7) / 8 * 8);
  }
}

}  // namespace

void WriteMatImage(const std::string& path, const std::string& variable, const ImageF& image) {
  const std::size_t h = image.height, w = image.width, k = image.channels;
  if (k != 1 && k != 3)
    throw std::invalid_argument(path + ": a MATLAB image needs 1 or 3 channels");
  std::vector<double> data(h * w * k);
  for (std::size_t r = 0; r < h; ++r)
    for (std::size_t c = 0; c < w; ++c)
      for (std::size_t i = 0; i < k; ++i)
        data[r + h * (c + w * i)] = image.pixels[k * (r * w + c) + i];  // MATLAB: column-major
  // matio writes only to paths and can report success on a full disk: the file is synced, then
  // read back and compared value by value.
  mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
  if (mat == nullptr) throw OutputError(path + ": cannot write: cannot create the MATLAB file");
  std::size_t dims[3] = {h, w, k};
  matvar_t* var = Mat_VarCreate(variable.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, k == 3 ? 3 : 2, dims,
                                data.data(), 0);
  const bool ok = var != nullptr && Mat_VarWrite(mat, var, MAT_COMPRESSION_ZLIB) == 0;
  if (var) Mat_VarFree(var);
  if (Mat_Close(mat) != 0 || !ok) {
    throw OutputError(path + ": cannot write: matio could not write variable " + variable);
  }
  SyncWrittenFile(path);
  bool same = false;
  try {
    const ImageF back = ReadMatImage(path, variable, static_cast<int>(k));
    same = back.width == image.width && back.height == image.height && back.pixels == image.pixels;
  } catch (const std::exception&) {
  }
  if (!same) throw OutputError(path + ": cannot write: the file read back differs (disk full?)");
}

ImageF ReadMatImage(const std::string& path, const std::string& variable, int channels) {
  CheckMat5Complete(path);
  mat_t* mat = Mat_Open(path.c_str(), MAT_ACC_RDONLY);
  if (mat == nullptr) FailInput(path, "not a MATLAB file matio can read");
  matvar_t* info = Mat_VarReadInfo(mat, variable.c_str());
  if (info == nullptr) {
    Mat_Close(mat);
    FailInput(path, "has no variable " + variable);
  }
  const std::size_t k = static_cast<std::size_t>(channels);
  const bool rank_ok = k == 3 ? info->rank == 3 && info->dims[2] == 3
                              : info->rank == 2 || (info->rank == 3 && info->dims[2] == 1);
  const bool shape_ok = rank_ok && !info->isComplex && info->dims[0] > 0 && info->dims[1] > 0 &&
                        info->dims[0] * info->dims[1] <= (std::size_t{1} << 31) &&
                        (info->class_type == MAT_C_DOUBLE || info->class_type == MAT_C_SINGLE);
  Mat_VarFree(info);
  if (!shape_ok) {
    Mat_Close(mat);
    FailInput(path, variable + " must be a real H x W" + (k == 3 ? " x 3" : "") +
                        " array of double or single");
  }
  matvar_t* var = Mat_VarRead(mat, variable.c_str());
  Mat_Close(mat);
  if (var == nullptr || var->data == nullptr) {
    if (var) Mat_VarFree(var);
    FailInput(path, "cannot read variable " + variable + " (corrupt file?)");
  }
  struct Free {
    matvar_t* v;
    ~Free() { Mat_VarFree(v); }
  } free_var{var};
  const std::size_t h = var->dims[0], w = var->dims[1];
  const std::size_t element = var->class_type == MAT_C_DOUBLE ? sizeof(double) : sizeof(float);
  if (var->nbytes < h * w * k * element) {
    FailInput(path, variable + " holds fewer values than its size says (corrupt file?)");
  }
  ImageF image(static_cast<int>(w), static_cast<int>(h), channels);
  auto value = [&](std::size_t i) -> double {
    return var->class_type == MAT_C_DOUBLE ? static_cast<const double*>(var->data)[i]
                                           : static_cast<const float*>(var->data)[i];
  };
  for (std::size_t r = 0; r < h; ++r)
    for (std::size_t c = 0; c < w; ++c)
      for (std::size_t i = 0; i < k; ++i)
        image.pixels[k * (r * w + c) + i] = static_cast<float>(value(r + h * (c + w * i)));
  return image;
}

void WriteNormalMat(const std::string& path, const std::string& variable, const ImageF& normals) {
  WriteMatImage(path, variable, normals);
}

ImageF ReadNormalMat(const std::string& path, const std::string& variable) {
  return ReadMatImage(path, variable, 3);
}

}  // namespace iphong::io
