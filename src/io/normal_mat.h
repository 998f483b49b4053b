// MATLAB files holding a normal map (DiLiGenT's Normal_gt.mat) or a depth map (Depth_gt.mat),
// read and written with matio.
#pragma once

#include <string>

#include "core/types.h"

namespace iphong::io {

// MATLAB files: an H×W×3 double array, as DiLiGenT's Normal_gt. The write is verified by reading
// the file back (OutputError); the read checks the file's structure first, since matio reads a
// truncated compressed array as zeros without a word.
void WriteNormalMat(const std::string& path, const std::string& variable, const ImageF& normals);
ImageF ReadNormalMat(const std::string& path, const std::string& variable);

// The same for 1 (H×W: a depth map, Depth_gt) or 3 channels.
void WriteMatImage(const std::string& path, const std::string& variable, const ImageF& image);
ImageF ReadMatImage(const std::string& path, const std::string& variable, int channels);

}  // namespace iphong::io
