// Pictures of results that people would rather look at than numbers.
#pragma once

#include <string>
#include <vector>

#include "core/resources.h"
#include "core/types.h"

namespace iphong::io {

// (n + 1)/2 per channel, 0 outside the mask. OpenGL convention (green = +y up) unless `directx`
// (green = −y, as DirectX tangent-space maps expect).
ImageF NormalMapPicture(const ImageF& normals, const Mask& mask, bool directx = false);

// The inverse, for normal maps stored as pictures: unit vectors from 2v − 1 (renormalized);
// black pixels (the outside of NormalMapPicture's mask) are left out of `mask` and set to 0.
ImageF NormalsFromPicture(const ImageF& picture, bool directx, Mask* mask);

// A normal-map file in any of the forms people keep them: float images (EXR, float TIFF: raw
// xyz), pictures (PNG, JPEG, TGA, BMP: (n + 1)/2, OpenGL convention unless `directx`; `mask` gets
// the pixels that are not black) or a MATLAB file (Normal_gt). Always 3 channels. Throws
// std::runtime_error naming the file ("needs 3 channels (x, y, z)").
ImageF ReadNormalMap(const std::string& path, bool directx, Mask* mask,
                     const MemoryLimit& memory = {});

// A normal map handed to a command (relight, fit-material, calibrate-lights --normals): every
// normal within `mask` (all pixels when null) finite and of unit length within 1 %, zero vectors
// being "no normal" there; throws std::runtime_error naming `path`, how many pixels are wrong
// and the first ("... 120 normals are not unit length (|n| = 2 at column 4, row 9)"). Returns
// the warning the map's own geometry gives when another frame of the image plane reads better
// (integrate/frame_check.h; not checked when most normals face away from the camera).
std::vector<std::string> CheckNormalMap(const ImageF& normals, const Mask* mask,
                                        const std::string& path);
// Its first half, for writers: the same refusals, no frame check. Returns the pixels with a
// normal; counts those facing away from the camera when asked.
Mask RequireUnitNormals(const ImageF& normals, const Mask* mask, const std::string& path,
                        std::size_t* facing_away = nullptr);

// The scale an error map is drawn to: the 99th percentile of the errors inside the mask, rounded
// up to 1, 2 or 5 × 10^k (at least 1e-6), so the map shows where the error is whatever
// its size (a 0.08° error on a 0-10° scale is uniformly blue).
double ErrorMapScale(const ImageF& error_deg, const Mask& mask);

// Angular error (degrees, 1 channel) as a colour map from 0 to `max_deg` with a labelled scale
// bar on the right; black outside the mask. Written as an 8-bit PNG (atomically).
// `unit` titles the scale ("deg"; "rms" for residuals).
void WriteErrorMap(const std::string& path, const ImageF& error_deg, const Mask& mask,
                   double max_deg, const std::string& unit = "deg");

// An albedo (or any linear colour image) as people look at it: scaled so its 99th percentile is
// 0.8 (render::AlbedoDisplayScale; albedos absorb the light intensities), sRGB, 8-bit.
void WriteAlbedoPicture(const std::string& path, const ImageF& albedo, const Mask& mask);

// A sheet of tiles (tile_width × tile_height, left to right, top to bottom; linear RGB) with a
// strip of label_height pixels under each row of tiles, each tile's label centred in it.
ImageF LabelTiles(const ImageF& sheet, int tile_width, int tile_height, int label_height,
                  const std::vector<std::string>& labels);

}  // namespace iphong::io
