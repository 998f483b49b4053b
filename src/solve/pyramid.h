// An image pyramid of photometric observations, for solvers that work coarse to fine.
//
// Level l + 1 halves level l in each direction: coarse pixel (c, r) covers fine pixels
// (2c … 2c+1, 2r … 2r+1). It is inside the mask when at least half of those that lie in the image
// are, and its observations are the mean of its inside children's (linear values, so the mean is
// what a camera with pixels twice as large would have recorded). Rows from the top; the lights
// are the fine level's.
#pragma once

#include <vector>

#include "core/types.h"
#include "solve/photometric_data.h"

namespace iphong::solve {

// The next coarser level of `fine` (width and height rounded up).
PhotometricData HalveObservations(const PhotometricData& fine);

// Levels 0 (= `fine`) … L: halved until a level has at most `coarsest_pixels` masked pixels
// (or the next would have none), and at most `max_levels` levels in all.
std::vector<PhotometricData> ObservationPyramid(const PhotometricData& fine,
                                                std::size_t coarsest_pixels, int max_levels);

// Unit normals of `coarse`'s masked pixels (one per pixel, in its order) carried to `fine`'s
// (the level it was halved from): bilinear between the coarse pixel centres around each fine
// pixel's centre, over the neighbours inside the coarse mask, then normalized; a fine pixel with
// none of them takes its nearest inside coarse pixel within two, else (0, 0, 1).
std::vector<Vec3d> UpsampleNormals(const PhotometricData& coarse,
                                   const std::vector<Vec3d>& coarse_normals,
                                   const PhotometricData& fine);

}  // namespace iphong::solve
